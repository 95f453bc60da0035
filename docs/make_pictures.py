"""The pictures of the docs, drawn again from the current code (CI runs this, so no
picture is older than the code it shows)::

    MUJOCO_GL=egl python docs/make_pictures.py            # every picture
    python docs/make_pictures.py --only dashboard         # one of them

- ``docs/dashboard.png``: the dashboard of an example-style suite (``SUITE`` below:
  flights, a fleet, a sweep, an xfail test whose budgets break, a test that flies
  nothing and attaches a robustness map, a skipped one), run twice, the second
  time on a Raspberry Pi 4 instead of a Jetson Nano against the first run's
  baseline; a screenshot at 1280 px in headless Chromium;
- ``docs/img/energy-breakdown.png`` and ``docs/img/flight-path.png``: the paper's
  scenario 1-B (``example_tests/scenarios.py``);
- ``docs/img/conditions.png`` and ``figures.png`` come from ``conditions_figure.py``.

``tests/reports/test_dashboard_browser.py`` runs the same suite and checks its dashboard in
the browser.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

SUITE = '''
import os

import numpy as np
import pandas as pd
import pytest

import pytest_flockai as fa
from pytest_flockai import plots
from pytest_flockai.budgets import check
from pytest_flockai.ml import PythonModel

DEVICE = os.environ.get("SUITE_DEVICE", "jetson-nano-10w")
HOVER = fa.pilots.Hover(altitude=2.0, duration=2.0)


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=HOVER)
@pytest.mark.kpi(crashed="== 0", battery_remaining=">= 80%")
def test_crazyflie_hovers(flight):
    pass


@pytest.mark.parametrize("speed", [3.0, 6.0])
@pytest.mark.kpi(crashed="== 0", energy_total_j="<= 5 kJ")
def test_mavic_survey_leg(speed):
    pilot = fa.pilots.Waypoints([(0, 0, 5), (20, 0, 5), (20, 10, 5)], speed=speed)
    fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, name="leg").run()


@pytest.mark.kpi(inference_latency_p50_s="<= 0.1 s", crashed="== 0")
def test_detector_on_board():
    task = fa.Task(PythonModel(lambda f: 0.0, macs=5e8, name="detector"), name="det",
                   period_s=0.5)
    fa.Mission(fa.drone("dji-mavic-2-pro", device=DEVICE), HOVER, tasks=[task],
               name="detect").run()


@pytest.mark.xfail(reason="the long-range battery is not in yet", strict=True)
@pytest.mark.flockai(drone="crazyflie-2-1", pilot=HOVER)
@pytest.mark.kpi(flight_time_s=">= 10 min", battery_remaining=">= 99%")
def test_long_range_battery(flight):
    pass


@pytest.mark.kpi({"fleet.crashes": "== 0", "fleet.min_separation_m": ">= 5 m"})
def test_two_drone_fleet():
    legs = [fa.pilots.Waypoints([(x, 0, 5), (x, 12, 5)], speed=4.0) for x in (0.0, 10.0)]
    fa.Fleet([fa.FleetDrone(f"drone-{i + 1}", fa.drone("dji-mavic-2-pro"), p, pad=(10.0 * i, 0),
                            seed=i) for i, p in enumerate(legs)]).run()


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=HOVER)
@pytest.mark.flockai_sweep(payload_kg=[0.0, 0.004], wind_mps=[0.0, 2.0], workers=1)
@pytest.mark.kpi(flight_time_s=">= 5 s")
def test_payload_and_wind_envelope(flockai_sweep):
    pass


def test_detector_robustness_map(record_property, tmp_path):
    """Scores only (no flight): a robustness map attached to the dashboard."""
    alt, speed = np.meshgrid([15.0, 25.0, 35.0], [0.0, 8.0, 16.0])
    recall = np.clip(0.9 - 0.012 * np.abs(alt - 30.0) - 0.025 * speed, 0, 1)
    df = pd.DataFrame({"altitude_m": alt.ravel(), "speed_mps": speed.ravel(),
                       "recall": recall.ravel()})
    for png in plots.save_envelope(df, tmp_path / "recall"):
        if png.suffix == ".png":
            record_property("flockai_picture", ("robustness map: detector recall", str(png)))
    check({"recall": float(recall.max())}, recall=">= 0.6")


@pytest.mark.skip(reason="needs the GPU runner")
def test_on_the_gpu_runner():
    pass
'''


def run_suite(folder: Path, device: str = "jetson-nano-10w", baseline: Path | None = None,
              extra=()) -> tuple[int, Path]:
    """Run ``SUITE`` in ``folder`` (a fresh pytest process); -> (exit status, dashboard)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "test_example_style.py").write_text(SUITE)
    html = folder / f"dashboard-{device}.html"
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "0",
           "--rootdir", str(folder), "--flockai-html", str(html),
           "--flockai-json", str(folder / f"report-{device}.json"),
           "--flockai-artifacts", str(folder / "artifacts"), *extra]
    if baseline is None:
        cmd += ["--flockai-save", str(folder / "baseline.json")]
    else:
        cmd += ["--flockai-baseline", str(baseline)]
    env = {**os.environ, "SUITE_DEVICE": device, "PYTHONPATH": str(ROOT)}
    env.pop("GITHUB_STEP_SUMMARY", None)
    rc = subprocess.run(cmd + ["test_example_style.py"], cwd=folder, env=env,
                        capture_output=True, text=True).returncode
    return rc, html


def chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        if shutil.which(name):
            return shutil.which(name)
    return None


def screenshot(url: str, png: Path, width: int, height: int) -> None:
    """A headless Chromium screenshot of ``url``."""
    browser = chromium()
    if browser is None:
        raise SystemExit("no Chromium installed (apt-get install chromium)")
    subprocess.run([browser, "--headless=new", "--no-sandbox", "--disable-gpu",
                    "--disable-dev-shm-usage", "--hide-scrollbars", f"--window-size={width},{height}",
                    f"--screenshot={png}", url], check=True, capture_output=True, timeout=120)


def dashboard(out: Path, widths=(1280,)) -> list[Path]:
    """The example-style suite's dashboard (second run: the computer swapped)."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        run_suite(folder)
        _, html = run_suite(folder, "raspberry-pi-4", baseline=folder / "baseline.json")
        written = []
        for w in widths:
            png = out / ("dashboard.png" if w == 1280 else f"dashboard-{w}.png")
            screenshot(html.as_uri(), png, w, 1600)
            written.append(png)
        return written


def scenario_1b(img: Path) -> list[Path]:
    """The energy breakdown and the flight path of the paper's scenario 1-B."""
    sys.path.insert(0, str(ROOT / "example_tests"))
    import scenarios

    import pytest_flockai as fa
    from pytest_flockai import plots
    r = scenarios.mission("1-B", {"cnn": scenarios.cnn()}).run()
    assert isinstance(r, fa.FlightResult)
    return [plots.energy_figure(r, img / "energy-breakdown.png"),
            plots.path_figure(r, img / "flight-path.png")]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=["dashboard", "scenario", "conditions"], default=None)
    ap.add_argument("--out", type=Path, default=HERE, help="where docs/ is (default: here)")
    a = ap.parse_args(argv)
    (a.out / "img").mkdir(parents=True, exist_ok=True)
    if a.only in (None, "dashboard"):
        print(*dashboard(a.out), sep="\n")
    if a.only in (None, "scenario"):
        print(*scenario_1b(a.out / "img"), sep="\n")
    if a.only in (None, "conditions") and a.out == HERE:
        subprocess.run([sys.executable, str(HERE / "conditions_figure.py")], check=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
