"""A sweep on a Dask cluster, and what it does when a worker dies.

Dask runs the tasks of a worker that dies on the other workers by itself, until
``distributed.scheduler.allowed-failures`` (3 by default) workers died under one
task; then the task fails with ``KilledWorker``. A variant that kills every worker
it flies on (``os._exit``, a crash in native code, the OOM killer) could so take
four workers down, and with none left the sweep's tasks would wait for a worker
for ever. The sweep bounds both, whatever the scheduler's settings:

- Each task carries a ticket, a ``distributed.Event`` that the task sets when it
  starts flying and clears when it is done (a lost task's ticket stays set until the
  sweep ends, and its future is released at once, so that Dask does not compute it
  again). A task that Dask runs again after its worker died finds its ticket set and
  flies nothing (``Lost``); a task that fails
  with ``KilledWorker`` or is cancelled (the base mission, scattered to the workers,
  was lost with the last worker that held it) counts as started when its ticket is set.
- The variants of a task whose worker died while it flew fly again, once
  (``REFLIGHTS``), each alone: one task, after the others, with nothing else in
  flight. An innocent variant that shared the dying worker gets its real row; a
  variant whose worker dies again is the row ``"worker died: tcp://a, then tcp://b
  died under it (2 tries)"`` (the addresses from the scheduler's ``remove-worker``
  events, or ``KilledWorker``'s last worker). A task lost before it started flying is
  sent again, at most ``REQUEUES`` times.
- When the cluster has no worker, the sweep waits for one with
  ``Client.wait_for_workers`` at most ``no_worker_s()``: Dask's own
  ``distributed.scheduler.no-workers-timeout`` where it is set (in the Dask config of
  the process that calls the sweep), else ``NO_WORKER_S``. Then every variant not back
  is the row ``"not flown: no Dask worker left (...)"``, and the sweep returns the
  rows it has.
"""

from __future__ import annotations

import uuid
from collections import defaultdict
from dataclasses import dataclass

from ..errors import ConfigError
from . import worker as _worker

#: times a variant whose worker died under it flies again (alone)
REFLIGHTS = 1
#: times a task lost before it started flying (its base lost, ``KilledWorker``) is sent again
REQUEUES = 3
#: s the sweep waits for a worker when the cluster has none, unless Dask's config sets
#: ``distributed.scheduler.no-workers-timeout`` (the scheduler address' connect timeout)
NO_WORKER_S = 30.0
#: s between checks of the sweep's tasks (a wait is also where an interrupt lands)
WAIT_S = 0.5


@dataclass(frozen=True)
class Lost:
    """The answer of a task Dask ran again after its worker died under it: nothing flown."""


def no_worker_s() -> float:
    """How long a sweep waits for a Dask worker when none is left (s)."""
    import dask.config
    from dask.utils import parse_timedelta
    value = dask.config.get("distributed.scheduler.no-workers-timeout", None)
    return float(parse_timedelta(value)) if value is not None else NO_WORKER_S


def run_once(ticket: str, job, batch: list, blob=None):
    """``worker.run_batch`` on a Dask worker, once per ticket: a task that Dask runs
    again after its worker died under it answers ``Lost`` and flies nothing."""
    from distributed import Event
    event = Event(ticket)
    if event.is_set():
        return Lost()
    event.set()
    answer = _worker.run_batch(job, batch, blob)
    event.clear()
    return answer


def fly(client, job, plan: list, todo: list, sink, batch_size: int, submit_kw=None) -> None:
    """Fly ``todo`` on the cluster of ``client``, ``batch_size`` variants per task,
    until each has a row (see the module's docstring)."""
    run = _Run(client, job, plan, sink, dict(submit_kw or {}))
    try:
        if not run.workers_left():
            run.give_up(todo)
            return
        for k in range(0, len(todo), batch_size):
            run.submit(todo[k:k + batch_size])
        run.drain()
        while run.alone:                        # the variants whose worker died: one by one
            run.submit([run.alone.pop(0)])
            run.drain()
    except BaseException:
        run.cancel()
        raise
    finally:
        run.clear_tickets()


class _Run:
    """One sweep's tasks on a Dask cluster."""

    def __init__(self, client, job, plan, sink, submit_kw):
        from distributed import Event
        self.client, self.plan, self.sink, self.Event = client, plan, sink, Event
        self.blob_bytes, self.job = job.blob, job.without_blob()
        self.kw = {k: v for k, v in submit_kw.items() if k != "pure"}
        self.wait_s, self.gone = no_worker_s(), False
        self.token, self.count, self.blob = uuid.uuid4().hex, 0, None
        self.pending: dict = {}                 # future -> (variant indices, ticket)
        self.alone: list[int] = []              # to fly again, alone
        self.deaths: dict = defaultdict(list)   # variant -> workers that died under it
        self.requeues: dict = defaultdict(int)
        self.seen: set = set()                  # worker addresses seen during the sweep
        self.tickets: list[str] = []            # to clear when the sweep ends

    # -- sending -----------------------------------------------------------------------------------
    def submit(self, ids: list) -> None:
        if not self._ensure_blob():
            self.give_up(ids)
            return
        self.count += 1
        ticket = f"flockai-sweep-{self.token}-{self.count}"
        f = self.client.submit(run_once, ticket, self.job, [(i, self.plan[i]) for i in ids],
                               self.blob, pure=False, **self.kw)
        self.pending[f] = (ids, ticket)

    def _ensure_blob(self) -> bool:
        """The base mission on the workers (scattered again when the last worker that
        held it died); False when no worker is left."""
        if self.blob is not None and self.blob.status == "finished":
            return True
        for _ in range(2):                      # a worker may leave while it is sent
            if not self.workers_left():
                return False
            try:
                self.blob = self.client.scatter(self.blob_bytes, broadcast=True, hash=False,
                                                timeout=self.wait_s)
                return True
            except TimeoutError:
                pass
        self.gone = True
        return False

    def workers_left(self) -> bool:
        """Whether the cluster has a worker, waiting up to ``wait_s`` for one to join."""
        if self.gone:
            return False
        workers = self.client.scheduler_info()["workers"]
        self.seen.update(workers)
        if not workers:
            try:
                self.client.wait_for_workers(1, timeout=self.wait_s)
            except TimeoutError:
                self.gone = True
        return not self.gone

    # -- taking answers ----------------------------------------------------------------------------
    def drain(self) -> None:
        """Take answers until no task is pending; give up when no worker is left."""
        from distributed import wait
        while self.pending:
            try:
                wait(list(self.pending), timeout=WAIT_S, return_when="FIRST_COMPLETED")
            except Exception:                   # noqa: BLE001 - a timeout, or a task cancelled:
                pass                            # each future's status says which
            done = [f for f in self.pending if f.done()]
            for f in done:
                if f in self.pending:           # not given up while taking another
                    self._take(f, *self.pending.pop(f))
                    f.release()                 # else Dask may compute it again
            if not done and self.pending and not self.workers_left():
                self.give_up([])

    def _take(self, f, ids: list, ticket: str) -> None:
        if f.status == "finished":
            try:
                answer = f.result(timeout=self.wait_s)
            except Exception:                   # noqa: BLE001 - the result was lost on the way
                answer = Lost() if self._started(ticket) else None
            if answer is None or isinstance(answer, Lost):
                self._lost(f, ids, ticket, answer is not None, None)
            elif isinstance(answer, _worker.Unloadable):
                raise ConfigError(answer.text)
            else:
                for i, outcome in answer:
                    self.sink(i, outcome)
            return
        exc = f.exception(timeout=self.wait_s) if f.status == "error" else None
        if exc is None or type(exc).__name__ == "KilledWorker":
            last = getattr(getattr(exc, "last_worker", None), "address", None)
            self._lost(f, ids, ticket, self._started(ticket), last)
            return
        self._clear(ticket)
        if len(ids) > 1:                        # a task failed without an answer: split once
            for i in ids:
                self.submit([i])
            return
        for i in ids:
            self.sink(i, _worker.failed(self.plan[i], f"not flown: {_worker.describe(exc)[0]}"))

    def _lost(self, f, ids: list, ticket: str, started: bool, address) -> None:
        """A task's worker died: under it (``started``), or before it began."""
        self._clear(ticket)
        if not started:
            for i in ids:
                self.requeues[i] += 1
                if self.requeues[i] > REQUEUES:
                    self.sink(i, _worker.failed(self.plan[i], (
                        f"not flown: the cluster lost its task {self.requeues[i]} times before "
                        f"it started (CancelledError or KilledWorker)")))
                else:
                    self.submit([i])
            return
        address = address or self._died_under(f.key)
        for i in ids:
            self.deaths[i].append(address or "a worker")
            if len(self.deaths[i]) > REFLIGHTS:
                self.sink(i, _worker.failed(self.plan[i], died_text(self.deaths[i])))
            else:
                self.alone.append(i)

    def give_up(self, ids: list) -> None:
        """No worker is left: rows for ``ids``, the pending tasks and those to fly again."""
        where = getattr(self.client.scheduler, "address", None) or "the scheduler"
        text = (f"not flown: no Dask worker left (none joined {where} within "
                f"{self.wait_s:g} s)")
        pending, self.pending = self.pending, {}
        if pending:
            self.client.cancel(list(pending))
        for f, (fids, ticket) in pending.items():
            if self._started(ticket):           # its worker died under it, none came back
                for i in fids:
                    self.deaths[i].append(self._died_under(f.key) or "a worker")
            self._clear(ticket)
            ids = ids + fids
        ids, self.alone = ids + self.alone, []
        for i in ids:
            if len(self.deaths[i]) > REFLIGHTS:
                self.sink(i, _worker.failed(self.plan[i], died_text(self.deaths[i])))
            elif self.deaths[i]:
                self.sink(i, _worker.failed(self.plan[i], (
                    f"{text[:-1]}; {', then '.join(self.deaths[i])} died under it)")))
            else:
                self.sink(i, _worker.failed(self.plan[i], text))

    def cancel(self) -> None:
        """Stop the pending tasks (an interrupt, an error)."""
        pending, self.pending = self.pending, {}
        try:
            self.client.cancel(list(pending))
            for _, ticket in pending.values():
                self._clear(ticket)
        except Exception:                       # noqa: BLE001 - best effort on the way out
            pass

    # -- the cluster's record ----------------------------------------------------------------------
    def _started(self, ticket: str) -> bool:
        try:
            return bool(self.Event(ticket, client=self.client).is_set())
        except Exception:                       # noqa: BLE001 - no scheduler: not known to start
            return False

    def _clear(self, ticket: str) -> None:
        """Clear ``ticket`` when the sweep ends: until then a task whose answer was lost
        with its worker (and that Dask computes again) must still find it set."""
        self.tickets.append(ticket)

    def clear_tickets(self) -> None:
        for ticket in self.tickets:
            try:
                self.Event(ticket, client=self.client).clear()
            except Exception:                   # noqa: BLE001 - best effort on the way out
                pass
        self.tickets = []

    def _died_under(self, key) -> str | None:
        """The worker that died with ``key`` in flight, from the scheduler's events of
        the workers this sweep has seen and that are gone."""
        try:
            departed = self.seen - set(self.client.scheduler_info()["workers"])
            for address in sorted(departed):
                for _, msg in reversed(list(self.client.get_events(address))):
                    if isinstance(msg, dict) and msg.get("action") == "remove-worker" \
                            and key in (msg.get("processing-tasks") or ()):
                        return address
        except Exception:                       # noqa: BLE001 - the address is a courtesy
            pass
        return None


def died_text(addresses: list) -> str:
    """A variant's row when its worker died in each of its tries."""
    return (f"worker died: {', then '.join(addresses)} died under it "
            f"({len(addresses)} tries)")
