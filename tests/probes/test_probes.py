"""Monitoring probes and telemetry."""

import queue

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError
from pytest_flockai.probes import EnergyProbe, FunctionProbe, Metric, Probe

TABLE1 = ["cpu_utilization", "cpu_time_s", "io_time_s", "mem_utilization", "kbytes_in", "kbytes_out",
          "packets_in", "packets_out", "flight_time_s", "takeoff_time_s", "hover_time_s", "move_time_s",
          "accel_time_s", "landing_time_s", "energy_total_j", "energy_share_motors",
          "energy_share_proc", "energy_share_comm", "battery_remaining"]


class Speedo(Probe):
    name = "app"
    metrics = (Metric("speed_mps", "m/s", "ground speed", better=None, kind="gauge"),
               Metric("samples", "1", "how often I was asked", kind="counter"))

    def __init__(self, **kw):
        super().__init__(**kw)
        self.n = 0

    def bind(self, view):
        self.n = 0

    def collect(self, view):
        self.n += 1
        vx, vy, vz = view.velocity
        return {"speed_mps": float(np.sqrt(vx * vx + vy * vy + vz * vz)), "samples": float(self.n)}


@pytest.fixture(scope="module")
def flown():
    pilot = fa.pilots.ZigZag(area=((0, 0), (60, 40)), altitude=15, spacing=20, speed=6)
    return fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, probes=[Speedo(period_s=0.5)], seed=2).run()


def test_every_table1_metric_in_telemetry_with_sensible_values(flown):
    tel = flown.telemetry
    for m in TABLE1:
        assert m in tel.columns, m
    late = tel.dropna(subset=["flight_time_s"])
    parts = late[["takeoff_time_s", "hover_time_s", "move_time_s", "accel_time_s", "landing_time_s"]].sum(axis=1)
    assert np.allclose(parts, late.flight_time_s)
    for c in ("kbytes_in", "kbytes_out", "packets_in", "packets_out", "energy_total_j", "flight_time_s"):
        col = tel[c].dropna()
        assert (np.diff(col.values) >= 0).all(), c
    for c in ("energy_share_motors", "energy_share_proc", "energy_share_comm", "battery_remaining",
              "cpu_utilization", "mem_utilization"):
        col = tel[c].dropna()
        assert ((col >= 0) & (col <= 1)).all(), c
    k = flown.kpis
    assert k["flight_time_s"] == pytest.approx(
        sum(k[n] for n in ("takeoff_time_s", "hover_time_s", "move_time_s", "accel_time_s", "landing_time_s")),
        abs=1e-9)
    assert k["packets_out"] > 0 and k["kbytes_out"] > k["kbytes_in"] > 0


def test_custom_probe_metric_is_a_kpi_and_in_the_telemetry(flown):
    k = flown.kpis
    assert "app.speed_mps" in k and "app.samples" in k
    assert fa.kpis.get("app.speed_mps").unit == "m/s"
    samples = flown.probe_samples["app"]
    # sampled every 0.5 s of simulated time, plus the final sample
    assert np.allclose(np.diff(samples.index.values[:-1]), 0.5, atol=0.011)
    assert "app.speed_mps" in flown.telemetry.columns
    assert samples["app.speed_mps"].max() == pytest.approx(6.0, abs=0.6)


@pytest.mark.parametrize("ext", [".csv", ".parquet", ".jsonl"])
def test_save_load_roundtrip(flown, tmp_path, ext):
    if ext == ".parquet":
        pytest.importorskip("pyarrow")
    p = flown.save(tmp_path / f"flight{ext}")
    back = fa.FlightResult.load(p)
    assert back == flown
    assert back.kpis["app.speed_mps"] == flown.kpis["app.speed_mps"]
    if ext != ".jsonl":
        assert (tmp_path / f"flight{ext}.json").exists()
    # a changed KPI makes them differ
    back.kpis["flight_time_s"] += 1
    assert back != flown


def test_live_subscriptions_callback_and_queue():
    got, q = [], queue.Queue()
    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 3.0))
    m.subscribe(got.append).subscribe(q)
    r = m.run()
    assert got and q.qsize() == len(got)
    first = q.get_nowait()
    assert set(first) == {"t", "probe", "values"} and first["t"] == pytest.approx(1.0, abs=0.01)
    flight = [s for s in got if s["probe"] == "flight"]
    assert flight[-1]["values"]["flight_time_s"] == r.kpis["flight_time_s"]


def test_probe_failure_is_reported_and_flight_goes_on():
    def boom(view):
        raise RuntimeError("sensor bus timeout")
    bad = FunctionProbe("flaky", boom, [Metric("x")], period_s=0.5)
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 2.0), probes=[bad]).run()
    assert r.end_reason == "landed" and "flight_time_s" in r.kpis and "flaky.x" not in r.kpis
    assert r.probe_errors and r.probe_errors[0]["probe"] == "flaky"
    assert "sensor bus timeout" in r.probe_errors[0]["error"]


def test_collect_returning_garbage_is_named():
    unknown = FunctionProbe("app", lambda v: {"y": 1.0}, [Metric("x")])
    nan = FunctionProbe("app2", lambda v: {"x": "fast"}, [Metric("x")])
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0), probes=[unknown, nan]).run()
    msgs = " | ".join(e["error"] for e in r.probe_errors)
    assert "probe 'app': collect() returned unknown metric 'y'" in msgs
    assert "probe 'app2': metric 'x' = 'fast' is not a number" in msgs


def test_disabled_probe_produces_nothing():
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0),
                   probes=[EnergyProbe(enabled=False)]).run()
    assert "energy_total_j" not in r.kpis and "flight_time_s" in r.kpis


def test_bad_probe_definitions():
    with pytest.raises(ConfigError, match="period_s = 0"):
        Speedo(period_s=0)
    with pytest.raises(ConfigError, match="metric 'flight_time_s' clashes with the built-in KPI"):
        fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0),
                   probes=[FunctionProbe("mine", lambda v: {}, [Metric("flight_time_s")])])
    with pytest.raises(ConfigError, match="clashes with a built-in probe"):
        fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0),
                   probes=[FunctionProbe("energy", lambda v: {}, [Metric("x")])])
    with pytest.raises(ConfigError, match="kind"):
        Metric("x", kind="histogram")


def test_phase_changes_are_events(flown):
    phases = [e["phase"] for e in flown.events if e["kind"] == "phase"]
    assert phases[0] == "takeoff" and phases[-1] == "landed"
    assert {"move", "accelerating", "landing"} <= set(phases)
    assert all(a != b for a, b in zip(phases, phases[1:]))


def test_a_sample_torn_by_the_watchdog_leaves_consistent_frames():
    """The wall-clock watchdog interrupts the flight between any two statements: a sample
    whose time was appended but not its row (or the reverse) is left out of the frames,
    instead of failing the partial result (pandas: "Length of values ... does not match")."""
    from pytest_flockai.probes.hub import ProbeHub
    hub = ProbeHub([Speedo(period_s=0.5)])
    ts, rows = hub.samples["app"]
    ts.extend([0.5, 1.0])
    rows.extend([(1.0, 1.0), (2.0, 2.0)])
    ts.append(1.5)                                  # torn: the time, not the row
    df = hub.frames()["app"]
    assert list(df.index) == [0.5, 1.0] and list(df["app.samples"]) == [1.0, 2.0]
    rows.extend([(3.0, 3.0), (4.0, 4.0)])          # torn the other way
    assert list(hub.frames()["app"].index) == [0.5, 1.0, 1.5]


def test_telemetry_torn_by_the_watchdog_keeps_the_rows_it_counted():
    """The watchdog can stop ``TelemetryRecorder.record`` between any two statements: after
    the row's index moved but not its count, and after a full chunk was kept but before the
    next was allocated. The frame holds the rows counted, once each, with the sensor
    columns (sliced to the same count) beside them, instead of failing the partial result."""
    from pytest_flockai.mission import loop
    from pytest_flockai.mission.assemble import Flight
    from pytest_flockai.mission.plan import resolve

    m = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=5.0, duration=3.0),
                   sensors=[fa.sensors.Barometer()], seed=0)
    flight = Flight([resolve(m)], [m])
    loop.fly(flight)
    rec = flight.runs[0].telemetry
    whole = rec.frame()
    n = rec.n
    assert n > 20 and len(whole) == n and any(c.startswith("sensor.") for c in whole.columns)
    rec._i += 1                                      # torn: index moved, count did not
    for hist in (rec._sensor_hist or {}).values():
        hist.append(hist[-1])
    torn = rec.frame()
    assert len(torn) == n and torn.index.equals(whole.index)
    rec._i -= 1                                      # torn at a chunk's end: kept, not renewed
    rec._buf, rec._t = rec._buf[: rec._i].copy(), rec._t[: rec._i].copy()
    rec._phase, rec._stage = rec._phase[: rec._i].copy(), rec._stage[: rec._i].copy()
    rec._full.append((rec._buf, rec._t, rec._phase, rec._stage))
    again = rec.frame()
    assert len(again) == n and again.index.equals(whole.index)
