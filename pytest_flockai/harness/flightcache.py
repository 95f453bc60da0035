"""The flight cache in pytest: one ``FlightCache`` per process under pytest's
cache directory (``<cache_dir>/d/flockai-flights``, shared by pytest-xdist
workers and kept across runs), opened around every test.

``--flockai-cache=off|read|write|readwrite|verify`` (default ``readwrite``) sets
the mode (``verify``: a sample of the hits, ``--flockai-cache-verify=FRACTION``,
default 0.1, is flown again and a test fails when it differs from its entry); flights inside hypothesis tests are not cached unless the test asks with
``@pytest.mark.flockai_cache("readwrite")`` (the marker sets any test's mode).
``--flockai-cache-clear`` empties the flight cache before the run. The cache is
off when pytest's cacheprovider plugin is (``-p no:cacheprovider``).
"""

from __future__ import annotations

import math
import os
from collections import Counter
from pathlib import Path

import pytest

from ..cache import MODES, VERIFY_FRACTION, Deferred, caching
from ..reports import summary as _summary
from .options import option
from .session import SESSION

CACHE_SUBDIR = "flockai-flights"
MARKER = "flockai_cache"


def add_options(parser) -> None:
    group = parser.getgroup("flockai")
    group.addoption("--flockai-cache", dest="flockai_cache", metavar="MODE", default=None,
                    choices=MODES,
                    help="reuse completed flights from pytest's cache directory when nothing "
                         "that shapes them changed: off, read, write, readwrite or verify "
                         "(default: readwrite; hypothesis tests: off unless marked "
                         "flockai_cache). Entries are authenticated with FLOCKAI_CACHE_KEY")
    group.addoption("--flockai-cache-verify", dest="flockai_cache_verify", metavar="FRACTION",
                    default=None, help="with --flockai-cache=verify: the share of cache hits "
                                       "flown again and compared (default 0.1)")
    parser.addini("flockai_cache", "ini form of --flockai-cache", type="string", default="")
    group.addoption("--flockai-cache-clear", dest="flockai_cache_clear", action="store_true",
                    default=False, help="remove every cached flight before the run")


def cache_dir(config) -> Path:
    """``<pytest cache_dir>/d/flockai-flights`` (resolved as pytest resolves cache_dir)."""
    raw = os.path.expanduser(os.path.expandvars(str(config.getini("cache_dir"))))
    base = Path(raw)
    if not base.is_absolute():
        base = Path(config.rootpath) / base
    return base / "d" / CACHE_SUBDIR


class CachePlugin:
    """Opens the flight cache around each test; counts what it did for the summary."""

    def __init__(self, config):
        self.config = config
        self.worker = hasattr(config, "workerinput")
        mode, _ = option(config, "cache")
        if mode is not None and mode not in MODES:
            raise pytest.UsageError(f"flockai_cache = {mode!r} is not allowed; allowed: "
                                    f"{', '.join(MODES)}")
        self.mode = mode or "readwrite"
        raw_fraction = config.getoption("flockai_cache_verify", None)
        if raw_fraction is not None and self.mode != "verify":
            raise pytest.UsageError(f"--flockai-cache-verify = {raw_fraction!r} needs "
                                    f"--flockai-cache=verify (the mode is {self.mode!r}: "
                                    f"nothing would be verified)")
        self.verify_fraction = _fraction(raw_fraction)
        self.off_reason = None
        if not config.pluginmanager.has_plugin("cacheprovider"):
            self.off_reason = "pytest's cacheprovider is disabled (-p no:cacheprovider)"
        self.directory = cache_dir(config) if self.off_reason is None else None
        self._caches: dict[str, Deferred] = {}
        config.addinivalue_line("markers", f"{MARKER}(mode): flight cache mode for this test "
                                           f"({', '.join(MODES)}; pytest-flockai)")
        if config.getoption("flockai_cache_clear", False) and not self.worker \
                and self.directory is not None:
            Deferred(self.directory).open().clear()      # the cache's own entries only

    def mode_for(self, item) -> tuple[str, str | None]:
        """(mode, error) for one test: its flockai_cache marker, else off for a
        hypothesis test, else the session's mode."""
        mark = item.get_closest_marker(MARKER)
        if mark is not None:
            mode = mark.args[0] if mark.args else mark.kwargs.get("mode")
            if mode not in MODES:
                return "off", (f"@pytest.mark.{MARKER}({mode!r}) is not allowed; allowed: "
                               f"{', '.join(MODES)}")
            return mode, None
        if getattr(getattr(item, "obj", None), "is_hypothesis_test", False):
            return "off", None
        return self.mode, None

    def cache_for(self, item) -> Deferred | None:
        if self.off_reason is not None:
            return None
        mode, _ = self.mode_for(item)
        if mode == "off":
            return None
        if mode not in self._caches:
            self._caches[mode] = Deferred(self.directory, mode,
                                          verify_fraction=self.verify_fraction)
        return self._caches[mode]

    @pytest.hookimpl(tryfirst=True)
    def pytest_runtest_setup(self, item):
        _, error = self.mode_for(item)
        if error:
            pytest.fail(error, pytrace=False)

    @pytest.hookimpl(wrapper=True)
    def pytest_runtest_protocol(self, item, nextitem):
        with caching(self.cache_for(item)):
            return (yield)

    def pytest_terminal_summary(self, terminalreporter, exitstatus, config):
        if self.worker:
            return
        line = summary_line(_flights(config), self.off_reason)
        if line:
            terminalreporter.write_line(line)


def _fraction(raw) -> float:
    """--flockai-cache-verify's value: a number in [0, 1] (UsageError otherwise)."""
    if raw is None:
        return VERIFY_FRACTION
    try:
        v = float(raw)
    except ValueError:
        v = math.nan
    if not 0 <= v <= 1:
        raise pytest.UsageError(f"--flockai-cache-verify = {raw!r} is not allowed; expected "
                                f"a fraction in [0, 1], e.g. 0.1")
    return v


def _flights(config) -> list[dict]:
    session = config.stash.get(SESSION, None)
    if session is None:
        return []
    return [f for e in session.entries() for f in e.get("flights", ())]


def summary_line(flights: list[dict], off_reason: str | None = None) -> str | None:
    """One line: how many flights came from the cache, were flown and stored, bypassed."""
    if off_reason is not None:
        return f"flockai cache: off ({off_reason})" if flights else None
    # a session fixture's flight is listed by every test that uses it: counted once, by the
    # rule the headline and the dashboard use
    flights = _summary.distinct_flights(flights, key=lambda f: (f.get("cache") or {}).get("key"))
    statuses = Counter((f.get("cache") or {}).get("status") for f in flights)
    statuses.pop(None, None)
    if not statuses:
        return None
    words = {"hit": "from the cache", "verified": "from the cache, flown again and verified",
             "stored": "flown and stored", "flown": "flown, not stored",
             "replaced": "flown, untrusted entry replaced", "bypass": "not cacheable"}
    parts = [f"{statuses[k]} {w}" for k, w in words.items() if statuses.get(k)]
    caches = [f.get("cache") or {} for f in flights]
    reasons = sorted({c["reason"] for c in caches
                      if c.get("status") in ("bypass", "replaced") and c.get("reason")})
    shown = "; ".join(r if len(r) <= 120 else r[:117] + "..." for r in reasons[:3])
    more = f"; and {len(reasons) - 3} more (flights[].cache in --flockai-json)" \
        if len(reasons) > 3 else ""
    tail = f" ({shown}{more})" if reasons else ""
    return "flockai cache: " + ", ".join(parts) + tail
