"""``run(cmd, drone, ...)``: fly the simulated drone with a real MAVLink program.

The runner checks its inputs, picks the app's ports, builds the flight (the drone on
its pad, motors off, waiting for the app's take-off; ``autopilot.Autopilot``), starts
the app in a process group of its own with its output in a file, flies the flight
paced at ``speed`` times the wall clock until the drone has landed and the app has
exited (or ``timeout_s``), then ends the whole process group (the app, its
``mavsdk_server``, any child) and returns an ``AppResult``. The flight is never taken
from the flight cache: the app is the thing under test.

Ports: by default (``port=None``) each run gets a free UDP port for MAVLink and a free
TCP port for MAVSDK's gRPC server, passed as ``FLOCKAI_MAVLINK_PORT``,
``FLOCKAI_MAVLINK_URL`` (``udpin://0.0.0.0:<port>``) and ``FLOCKAI_GRPC_PORT``; a Python
app that names PX4 SITL's ``14540`` (MAVSDK ``System.connect``, pymavlink
``mavlink_connection``) or MAVSDK's gRPC ``50051`` is redirected to them by a start-up
hook (``app/hook/sitecustomize.py`` on the app's ``PYTHONPATH``), so unchanged examples
run side by side. ``port=14540`` flies exactly as PX4 SITL's onboard instance does.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from dataclasses import dataclass

from .. import _check
from .. import kpis as _kpis
from ..airframe.drone import Drone
from ..control.pilots import Hover
from ..errors import ConfigError, FlockAIError, SimulationError
from ..mission import collect, loop
from ..mission.assemble import Flight
from ..mission.mission import Mission
from ..mission.plan import resolve
from ..recording import publish
from ..result import FlightResult
from .autopilot import Autopilot

HOOK_DIR = os.path.join(os.path.dirname(__file__), "hook")
PX4_PORT = 14540

for _name, _unit, _better, _what in (
        ("app.exit_code", "1", None, "the app's exit status (0: success)"),
        ("app.commands", "count", None, "MAVLink commands the app sent (requests for messages not counted)"),
        ("app.commands_denied", "count", "lower", "commands the autopilot refused (DENIED)"),
        ("app.commands_unsupported", "count", "lower", "commands and mission items not emulated"),
        ("app.geofence_breaches", "count", "lower", "times the drone left the geofence the app set"),
        ("app.speed", "1", None, "simulated seconds per wall second"),
        ("app.lag_max_s", "s", "lower", "most the simulation fell behind the paced wall clock"),
        ("app.lag_mean_s", "s", "lower", "mean lag of the simulation behind the paced wall clock")):
    _kpis.register(_name, _unit, _better, _what)


class AppError(FlockAIError, AssertionError):
    """The app hung (killed at its timeout) or the flight failed; ``.result`` is the
    partial ``FlightResult``, ``.output`` the app's stdout and stderr."""

    result: FlightResult | None
    output: str


@dataclass
class AppResult:
    """What an app flight gave: ``exit_code`` of the app, ``result`` the
    ``FlightResult`` (with the ``app.*`` KPIs), ``output`` its stdout and stderr."""

    exit_code: int
    result: FlightResult
    output: str
    wall_s: float
    port: int


def free_port(kind: int = socket.SOCK_DGRAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def check_port_free(port: int) -> None:
    """ConfigError when something already listens on UDP ``port`` (PX4 SITL, another app)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind(("0.0.0.0", port))
        except OSError as exc:
            raise ConfigError(f"app.run: port = {port} is in use ({exc.strerror}); another "
                              f"app, MAVSDK server or PX4 SITL listens there; stop it or pass "
                              f"port=None for a free port") from None


def _check_cmd(cmd) -> list:
    if isinstance(cmd, str) or not isinstance(cmd, (list, tuple)) or not cmd or \
            not all(isinstance(c, (str, os.PathLike)) for c in cmd):
        raise ConfigError(f"app.run: cmd = {cmd!r} is not allowed; expected a non-empty list "
                          f"of strings, e.g. [sys.executable, 'my_app.py']")
    cmd = [os.fspath(c) for c in cmd]
    exe = cmd[0]
    found = shutil.which(exe)
    if found is None:
        why = ("is not executable" if os.path.exists(exe) else "does not exist")
        raise ConfigError(f"app.run: cmd[0] = {exe!r} {why}; expected a program on PATH or a "
                          f"path with execute permission (e.g. [sys.executable, 'app.py'])")
    return cmd


def run(cmd, drone: Drone, *, world=None, tasks=(), speed: float = 1.0,
        timeout_s: float = 120.0, env: dict | None = None, port: int | None = None,
        seed: int = 0, wind=None, cwd=None, name: str | None = None) -> AppResult:
    """Fly ``drone`` with the MAVLink app ``cmd`` (module docstring). Raises
    ``AppError`` when the app is still running at ``timeout_s`` (wall seconds; it is
    killed first) with what it last sent and waited for."""
    if os.name != "posix":
        raise ConfigError(f"app.run: os.name = {os.name!r} is not supported; the app runs in a "
                          f"POSIX process group (Linux, macOS)")
    cmd = _check_cmd(cmd)
    speed = _check.positive("speed", speed, where="app.run")
    timeout_s = _check.positive("timeout_s", timeout_s, where="app.run")
    if env is not None and not (isinstance(env, dict) and all(
            isinstance(k, str) and isinstance(v, str) for k, v in env.items())):
        raise ConfigError(f"app.run: env = {env!r} is not allowed; expected None or a dict "
                          f"of str to str")
    if port is None:
        port, redirect = free_port(), True
    else:
        port = int(_check.positive("port", port, where="app.run"))
        check_port_free(port)
        redirect = False
    ap = Autopilot(port, speed)
    mission = Mission(drone, Hover(altitude=2.5), world=world, tasks=tasks, seed=seed, wind=wind,
                      fly_on="estimate", policies=[ap], name=name,
                      max_time_s=max(600.0, 2.0 * timeout_s * speed))
    app_env = dict(os.environ)
    app_env.update(env or {})
    app_env.update(FLOCKAI_MAVLINK_PORT=str(port), FLOCKAI_MAVLINK_URL=f"udpin://0.0.0.0:{port}",
                   FLOCKAI_GRPC_PORT=str(free_port(socket.SOCK_STREAM)),
                   PYTHONUNBUFFERED="1")
    if redirect:
        app_env["PYTHONPATH"] = os.pathsep.join(
            [HOOK_DIR] + [p for p in [app_env.get("PYTHONPATH", "")] if p])
    return _fly(cmd, mission, timeout_s, app_env, cwd, port, speed)


def _fly(cmd, mission, timeout_s, app_env, cwd, port, speed) -> AppResult:
    wall0 = time.perf_counter()
    flight = Flight([resolve(mission)], [mission])
    run_ = flight.runs[0]
    ap = run_.policies[0]
    deadline = time.monotonic() + timeout_s
    ap.deadline = deadline
    out = tempfile.TemporaryFile()
    try:
        proc = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                env=app_env, cwd=cwd, start_new_session=True)
    except OSError as exc:
        ap.link.close()
        out.close()
        raise ConfigError(f"app.run: cmd = {cmd!r} could not start: {exc}") from None
    ap.proc = proc
    err: SimulationError | None = None
    try:
        try:
            loop.fly(flight)
        except SimulationError as exc:
            err = exc
        t_end = run_.t_end if err is None else run_.data.time
        reason = run_.vehicle.end_reason if err is None else getattr(err, "end_reason", "diverged")
        try:
            code = proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            code = None
        diagnosis = ap.link.diagnosis()
    finally:
        _kill(proc)
        ap.link.close()
        out.seek(0)
        output = out.read().decode(errors="replace")
        out.close()
    if code is None or reason == "app_timeout":
        reason = "app_timeout"
    res = collect.flight_result(run_, mission, time.perf_counter() - wall0, t_end, reason)
    res.kpis.update({"app.exit_code": float(proc.returncode if code is None else code),
                     "app.commands": float(ap.commands), "app.commands_denied": float(ap.denied),
                     "app.commands_unsupported": float(ap.unsupported), "app.speed": speed,
                     "app.geofence_breaches": float(ap.gf_breaches),
                     "app.lag_max_s": ap.lag_max,
                     "app.lag_mean_s": ap.lag_sum / max(1, ap.n_steps)})
    res.scenario["app"] = {"cmd": list(cmd), "speed": speed, "port": port, "timeout_s": timeout_s}
    publish(res, mission)
    if err is not None:
        err.result = res
        raise err
    if code is None:
        raised = raised_in(output)
        if raised:          # an app that raised but did not exit: say so first
            diagnosis = (f"the app raised {raised} (its output ends in a Python traceback) "
                         f"but did not exit: a thread or child process (MAVSDK's "
                         f"mavsdk_server) kept it alive; {diagnosis}")
        e = AppError(f"app {cmd!r} was still running after timeout_s = {timeout_s:g} s and was "
                     f"killed with its process group; {diagnosis}; the drone was "
                     f"{'in the air' if ap.in_air else 'on the ground'} in mode {ap.mode} at "
                     f"t = {t_end:.1f} s of simulated time")
        e.result, e.output = res, output
        raise e
    return AppResult(int(code), res, output, time.perf_counter() - wall0, port)


def raised_in(output: str) -> str | None:
    """The exception line of the last Python traceback in ``output`` (e.g. ``KeyError:
    'x'``), or None when it has none."""
    at = output.rfind("Traceback (most recent call last):")
    if at < 0:
        return None
    for line in reversed(output[at:].splitlines()[1:]):
        if line.strip() and not line[0].isspace():
            return line.strip()[:200]
    return None


def marker_flight(request, mission, mark) -> FlightResult:
    """The ``flight`` fixture under ``@pytest.mark.flockai_app(cmd=[...], ...)``: the
    fixtures' drone, world, tasks, wind and seed flown by the app; its output goes into
    the test's report; a failing exit code fails the test."""
    if mark.args:
        raise ConfigError(f"flockai_app: positional arguments {mark.args!r} are not allowed; "
                          f"use cmd=[...], timeout_s=, speed=, env=, port=")
    kw = dict(mark.kwargs)
    allowed = ("cmd", "timeout_s", "speed", "env", "port")
    for k in kw:
        if k not in allowed:
            raise ConfigError(f"flockai_app: unknown argument {k!r}; allowed: {', '.join(allowed)}")
    if "cmd" not in kw:
        raise ConfigError("flockai_app: cmd is required, e.g. cmd=[sys.executable, 'app.py']")
    try:
        r = run(kw.pop("cmd"), mission.drone, world=mission.world, tasks=mission.tasks,
                seed=mission.seed, wind=mission.wind, name=mission.name,
                cwd=str(request.config.rootpath), **kw)
    except AppError as exc:
        request.node.add_report_section("call", "flockai app output", exc.output)
        raise
    request.node.add_report_section("call", "flockai app output", r.output)
    if r.exit_code != 0:
        raise AppError(f"the app exited with code {r.exit_code}:\n{r.output[-2000:]}")
    return r.result


def _kill(proc) -> None:
    """End the app's whole process group: SIGTERM, then SIGKILL after 2 s."""
    for sig, wait in ((signal.SIGTERM, 2.0), (signal.SIGKILL, 2.0)):
        try:
            os.killpg(proc.pid, sig)
        except (ProcessLookupError, PermissionError):
            break
        t0 = time.monotonic()
        while time.monotonic() - t0 < wait:
            if proc.poll() is not None and not _group_alive(proc.pid):
                return
            time.sleep(0.02)
    if proc.poll() is None:
        proc.wait(timeout=5)


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except (ProcessLookupError, PermissionError):
        return False
    return True
