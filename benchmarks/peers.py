"""Our batched sweep against peer simulators on the same job, in one interleaved run:
N Crazyflies hovering ``--seconds`` (default 10 s; N = 64 and 1,024), in drone-seconds
simulated per wall second and per CPU-second, with the load average beside every figure
(the machines are shared: read the ratios, taken round by round).

- **pytest-flockai**: ``fa.sweep(Mission(crazyflie-2-1, Hover(1 m, 10 s)), backend=...,
  device="cpu", payload_kg=<N values, 0 to 5 g>)``, the full model (rotor dynamics,
  body and rotor drag, H-force, motor and battery models, energy book, stages with
  take-off and landing); drone-seconds = the variants' simulated time (about 13 s each:
  take-off, 10 s hover, landing). The first call (compile, or a load from JAX's
  persistent cache) is timed apart. ``sweep`` is the whole ``fa.sweep`` call, ``batch``
  its batched part (``engine.LAST_TIMINGS``: without building each variant's numbers
  and MuJoCo model).
- **crazyflow** (``pip install crazyflow``, its own venv): ``Sim(n_worlds=N,
  control=Control.state)`` at its defaults (500 Hz first-principles dynamics), one
  state set-point at 1 m and ``sim.step(500 x seconds)``: one compiled call, XLA's pool
  over every CPU. Also **one thread per shard**, the way our batch runs: as many
  crazyflow processes as our batch has shards (``FLOCKAI_JAX_CPU_SHARDS``, default one
  per CPU), each pinned to its own CPU (so XLA starts one thread) with N / shards
  worlds, started together; wall = the slowest, CPU = the sum. Also ``--cf-loop``: a
  Python loop of 100 Hz set-points, ``sim.step(5)`` each.
- **PyFlyt** and **rotorpy** (optional, ``--peers``): single-drone Python loops, N
  drones one after another (capped by ``--loop-cap``, the rate scaled from it).

``--install`` creates the peers' venvs (``--venv-dir``, default
``~/.cache/pytest-flockai/peers/<peer>``; crazyflow also found at /work/venv-crazyflow)
and pip-installs them from PyPI; without it a peer whose venv is missing is skipped
with a line saying so.

    python benchmarks/peers.py [--n 64 1024] [--rounds 3] [--seconds 10] [--install]
        [--peers crazyflow pyflyt rotorpy] [--backend jax] [--cf-loop]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

import pytest_flockai as fa
from pytest_flockai.sweeps.batched import engine, shards

SECONDS = 10.0
PACKAGES = {"crazyflow": ["crazyflow"], "pyflyt": ["PyFlyt"], "rotorpy": ["rotorpy"]}
KNOWN_VENVS = {"crazyflow": [Path("/work/venv-crazyflow")]}

CRAZYFLOW = textwrap.dedent('''
    import json, os, sys, time
    import numpy as np
    from crazyflow.control import Control
    from crazyflow.sim import Sim
    n, seconds, loop = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3] == "1"
    sim = Sim(n_worlds=n, n_drones=1, control=Control.state)
    cmd = np.zeros((n, 1, 16)); cmd[..., 2] = 1.0; cmd[..., 12] = 1.0   # 1 m, qw = 1
    steps = int(seconds * sim.freq)
    def once():
        sim.reset()
        sim.data.states.pos.block_until_ready()
        t, c = time.perf_counter(), time.process_time()
        if loop:
            per = sim.freq // 100
            for _ in range(steps // per):
                sim.state_control(cmd); sim.step(per)
        else:
            sim.state_control(cmd); sim.step(steps)
        sim.data.states.pos.block_until_ready()
        return time.perf_counter() - t, time.process_time() - c
    first, _ = once()
    wall, cpu = once()
    z = float(np.mean(np.asarray(sim.data.states.pos)[..., 2]))
    print(json.dumps({"first_s": first, "wall_s": wall, "cpu_s": cpu, "drone_s": n * seconds,
                      "z": z}))
''')

PYFLYT = textwrap.dedent('''
    import json, sys, time
    import numpy as np
    from PyFlyt.core import Aviary
    n, seconds = int(sys.argv[1]), float(sys.argv[2])
    t0 = time.perf_counter()
    for _ in range(n):
        env = Aviary(start_pos=np.array([[0.0, 0.0, 1.0]]), start_orn=np.zeros((1, 3)),
                     render=False, drone_type="quadx")
        env.set_mode(7)
        env.set_setpoint(0, np.array([0.0, 0.0, 0.0, 1.0]))
        for _ in range(int(seconds * 120)):
            env.step()
        env.disconnect()
    print(json.dumps({"first_s": 0.0, "wall_s": time.perf_counter() - t0, "drone_s": n * seconds}))
''')

ROTORPY = textwrap.dedent('''
    import json, sys, time
    import numpy as np
    from rotorpy.controllers.quadrotor_control import SE3Control
    from rotorpy.simulate import simulate
    from rotorpy.trajectories.hover_traj import HoverTraj
    from rotorpy.vehicles.crazyflie_params import quad_params
    from rotorpy.vehicles.multirotor import Multirotor
    from rotorpy.wind.default_winds import NoWind
    from rotorpy.world import World
    n, seconds = int(sys.argv[1]), float(sys.argv[2])
    x0 = {"x": np.array([0.0, 0.0, 1.0]), "v": np.zeros(3), "q": np.array([0, 0, 0, 1.0]),
          "w": np.zeros(3), "wind": np.zeros(3), "rotor_speeds": np.ones(4) * 1788.53}
    t0 = time.perf_counter()
    for _ in range(n):
        simulate(World({"bounds": {"extents": [-10, 10, -10, 10, -10, 10]}, "blocks": []}),
                 x0, Multirotor(quad_params), SE3Control(quad_params), HoverTraj(np.array([0, 0, 1.0])),
                 NoWind(), [], seconds, 1 / 500, safety_margin=0.25, use_mocap=False,
                 terminate=False)
    print(json.dumps({"first_s": 0.0, "wall_s": time.perf_counter() - t0, "drone_s": n * seconds}))
''')
SCRIPTS = {"crazyflow": CRAZYFLOW, "pyflyt": PYFLYT, "rotorpy": ROTORPY}


def _load() -> str:
    return " ".join(f"{x:.1f}" for x in os.getloadavg())


def venv_of(peer: str, root: Path) -> Path:
    """The peer's venv: ``root/<peer>``, or a known one that exists."""
    for known in KNOWN_VENVS.get(peer, []):
        if (known / "bin" / "python").exists():
            return known
    return root / peer


def install(peer: str, root: Path) -> Path:
    """Create ``peer``'s venv and pip-install it from PyPI (its own dependencies, pinned
    by pip, apart from ours)."""
    venv = venv_of(peer, root)
    if not (venv / "bin" / "python").exists():
        venv.parent.mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet",
                    *PACKAGES[peer]], check=True)
    return venv


def peer_run(peer: str, venv: Path, n: int, loop: bool = False, cap: int = 0,
             pinned: int = 0) -> dict | None:
    """One measurement of ``peer`` in its venv (a fresh process: its first call is timed
    apart); ``pinned`` > 0: that many processes started together, each on its own CPU
    with n / pinned drones (wall: the slowest, CPU and drone-seconds: the sums). None,
    with the reason printed, if it failed."""
    runs = min(n, cap) if cap and peer != "crazyflow" else n
    cpus = sorted(os.sched_getaffinity(0))
    procs = []
    for j in range(max(1, pinned)):
        share = runs // pinned + (j < runs % pinned) if pinned else runs
        cmd = [str(venv / "bin" / "python"), "-c", SCRIPTS[peer], str(share), str(SECONDS),
               "1" if loop else "0"]
        if pinned:                           # XLA sizes its pool from the affinity
            cmd = ["taskset", "-c", str(cpus[j % len(cpus)]), *cmd]
        procs.append(subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                      text=True))
    got = []
    for proc in procs:
        stdout, stderr = proc.communicate(timeout=3600)
        lines = [ln for ln in stdout.splitlines() if ln.startswith("{")]
        if proc.returncode != 0 or not lines:
            print(f"  {peer}: failed (rc {proc.returncode}): {stderr.strip().splitlines()[-1:]}")
            return None
        got.append(json.loads(lines[-1]))
    res = {"first_s": max(g["first_s"] for g in got), "wall_s": max(g["wall_s"] for g in got),
           "drone_s": sum(g["drone_s"] for g in got)}
    if all("cpu_s" in g for g in got):
        res["cpu_s"] = sum(g["cpu_s"] for g in got)
    res["drone_s"] *= n / runs               # a capped loop: the same rate over N drones
    res["wall_s"] *= n / runs
    return res


def ours(n: int, backend: str) -> dict:
    """One timed ``fa.sweep`` of N hovering Crazyflies (warm: compiled in this process)."""
    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=SECONDS))
    payloads = list(np.linspace(0.0, 0.005, n))
    t0, c0 = time.perf_counter(), time.process_time()
    df = fa.sweep(m, backend=backend, device="cpu", payload_kg=payloads)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    assert df["error"].isna().all() and (df["end_reason"] == "landed").all(), df["end_reason"]
    return {"wall_s": wall, "cpu_s": cpu, "drone_s": float(df["sim_time_s"].sum()),
            "batch_s": engine.LAST_TIMINGS.get("batch_s", wall),
            "batch_cpu_s": engine.LAST_TIMINGS.get("batch_cpu_s"), "ran": df.attrs["backend"],
            "shards": df.attrs.get("jax_cpu_shards")}


def _line(rnd, n, who, res) -> tuple:
    rate = res["drone_s"] / res["wall_s"]
    cpu = res["drone_s"] / res["cpu_s"] if res.get("cpu_s") else float("nan")
    extra = f"   first call {res['first_s']:.1f} s" if res.get("first_s") else ""
    print(f"{rnd:>5}{n:>7}  {who:<34}{res['wall_s']:>9.2f}{rate:>12.0f}{cpu:>12.0f}   "
          f"load {_load()}{extra}", flush=True)
    return rate, cpu


def main() -> None:
    global SECONDS
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[64, 1024])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=SECONDS, help="hover length (s)")
    ap.add_argument("--peers", nargs="*", default=["crazyflow"], choices=sorted(SCRIPTS))
    ap.add_argument("--backend", default="jax", choices=("jax", "mjx", "auto"))
    ap.add_argument("--install", action="store_true", help="create the peers' venvs and install")
    ap.add_argument("--venv-dir", type=Path,
                    default=Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
                    / "pytest-flockai" / "peers")
    ap.add_argument("--cf-loop", action="store_true", help="also crazyflow's Python loop")
    ap.add_argument("--loop-cap", type=int, default=8, help="drones flown by a per-drone loop")
    a = ap.parse_args()
    SECONDS = a.seconds
    n_shards = shards.wanted()
    venvs = {}
    for peer in a.peers:
        venv = install(peer, a.venv_dir) if a.install else venv_of(peer, a.venv_dir)
        if (venv / "bin" / "python").exists():
            venvs[peer] = venv
        else:
            print(f"{peer}: no venv at {venv} (run with --install); skipped")
    print(f"N Crazyflies hovering {SECONDS:g} s; {os.cpu_count()} CPU core(s), "
          f"{len(os.sched_getaffinity(0))} usable; our batch in {n_shards} shard(s); drone-s/s "
          f"= simulated drone-seconds per wall second")
    for n in a.n:                                    # compile (or load) once per size
        t0 = time.perf_counter()
        ours(n, a.backend)
        print(f"pytest-flockai first call at N = {n}: {time.perf_counter() - t0:.1f} s "
              f"(compile or persistent-cache load; load {_load()})", flush=True)
    print(f"{'round':>5}{'N':>7}  {'contender':<34}{'wall s':>9}{'drone-s/s':>12}"
          f"{'per CPU-s':>12}")
    rates: dict = {}
    for rnd in range(1, a.rounds + 1):
        for n in a.n:
            res = ours(n, a.backend)
            rates.setdefault((n, "sweep"), []).append(
                _line(rnd, n, f"fa.sweep {res['ran']}, {res['shards']} shard(s)", res))
            rates.setdefault((n, "batch"), []).append(
                _line(rnd, n, "  of which the batch", {**res, "wall_s": res["batch_s"],
                                                       "cpu_s": res["batch_cpu_s"]}))
            for peer, venv in venvs.items():
                for loop in ([False, True] if peer == "crazyflow" and a.cf_loop else [False]):
                    got = peer_run(peer, venv, n, loop, a.loop_cap)
                    if got is not None:
                        name = peer + (" (Python loop)" if loop else "")
                        rates.setdefault((n, name), []).append(_line(rnd, n, name, got))
                if peer == "crazyflow" and n_shards > 1:
                    got = peer_run(peer, venv, n, pinned=n_shards)
                    if got is not None:
                        name = f"crazyflow, 1 thread x {n_shards}"
                        rates.setdefault((n, name), []).append(_line(rnd, n, name, got))
    print("\nmedians over the rounds (drone-s per wall s; per CPU-s of the process, which the "
          "load\nchanges less), and ratios to crazyflow (one compiled call):")
    for n in a.n:
        base = rates.get((n, "crazyflow"))
        cf = [statistics.median(x[i] for x in base) for i in (0, 1)] if base else None
        for (nn, who), vals in rates.items():
            if nn != n:
                continue
            med = [statistics.median(x[i] for x in vals) for i in (0, 1)]
            ratio = (f"   x{med[0] / cf[0]:.2f} wall, x{med[1] / cf[1]:.2f} CPU of crazyflow"
                     if cf else "")
            print(f"  N = {n:>5}  {who:<28}{med[0]:>10.0f}{med[1]:>10.0f}{ratio}")
    print(f"load average at the end: {_load()}")


if __name__ == "__main__":
    main()
