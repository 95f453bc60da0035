"""Robustness of the shipped detector (issue 19): where does it hold? Its recall
mapped over altitude x speed at a 1/30 s shutter (a CSV and a heat map as
artifacts), the envelope stated as a budget, and a hypothesis search that
finds the imaging condition breaking a recall budget and shrinks it."""

import os

import pytest
import scenarios
from hypothesis import Phase, given, settings

import pytest_flockai as fa
from pytest_flockai import plots
from pytest_flockai import strategies as fst
from pytest_flockai.budgets import check
from pytest_flockai.ml import FrameRecord, altitude_band, detection_kpis
from pytest_flockai.ml.envelope import envelope
from pytest_flockai.reports.compare import compare


@pytest.fixture(scope="session")
def recall_map(det_model, det_city, tmp_path_factory):
    df = envelope(det_model, det_city, altitudes_m=(15.0, 25.0, 35.0, 50.0),
                  speeds_mps=(0.0, 8.0, 16.0), conditions=fa.Conditions(exposure_s=1 / 30),
                  views=12, area=90.0, camera={"fov_deg": 51.0})
    out = os.environ.get("FLOCKAI_ENVELOPE_DIR") or tmp_path_factory.mktemp("envelope")
    written = plots.save_envelope(df, os.path.join(out, "detector-recall"))
    df.attrs["pictures"] = [str(p) for p in written if str(p).endswith(".png")]
    return df


def test_detector_envelope_over_altitude_and_speed(recall_map, record_property):
    """With a 1/30 s shutter, recall >= 0.6 holds from 25 m to 50 m when hovering; at
    8 m/s the blur costs it at every altitude and no altitude keeps 0.6; at 16 m/s it
    stays under 0.55, where the blur smears people away; below 20 m the figures seen
    from the side are outside what the detector learned."""
    assert altitude_band(recall_map, "recall", 0.6, speed_mps=0.0) == (25.0, 50.0)
    by = recall_map.pivot(index="altitude_m", columns="speed_mps", values="recall")
    assert (by[8.0] < by[0.0]).all() and by[8.0].max() < 0.6
    assert by[16.0].max() < 0.55
    low = recall_map[recall_map.altitude_m == 15.0].recall.max()
    assert low < 0.5
    for png in recall_map.attrs["pictures"]:     # the heat map, in the --flockai-html dashboard
        record_property("flockai_picture", ("robustness map: detector recall", png))


@pytest.fixture(scope="session")
def fixed_views(det_city):
    return fa.sensors.ViewSet(det_city, [(70.0, 50.0, 25.0, 0.0), (40.0, 40.0, 25.0, 1.0),
                                         (-60.0, 80.0, 25.0, 2.0)], {"fov_deg": 51.0})


#: derandomized, so the same frames are scored on every run: the flight cache's memo keeps
#: their COCO scores (the search's cost), as for the wind fuzz of test_what_ifs.py
@pytest.mark.flockai_cache("readwrite")
def test_a_tight_recall_budget_breaks_in_haze(fixed_views, det_model):
    """The search finds haze (the detector never saw it in training) and shrinks it.
    Hypothesis's explain phase (which arguments did not matter) is left out: it took
    three quarters of the search's time (32 of 42 s, profiled) for a note the test
    does not read; finding and shrinking the haze are unchanged."""
    @settings(max_examples=12, deadline=None, derandomize=True, database=None,
              phases=[p for p in Phase if p is not Phase.explain])
    @given(cond=fst.conditions(noise=False))
    def recall_holds(cond):
        frames = fixed_views.under(cond)
        recs = [FrameRecord(i, t.objects, fa.ml.parse_detections(
                    det_model(f), f.shape[:2], n_classes=2, where="det", score_threshold=0.05,
                    input_hw=det_model.input_size), 25.0, 320, 240)
                for i, (f, t) in enumerate(frames)]
        k = detection_kpis(recs, ("person", "vehicle"), score_threshold=0.4, min_visible=0.25)
        fst.target_margin(k, recall=">= 0.6")
        check(k, recall=">= 0.6")
    with pytest.raises(AssertionError, match="recall") as exc:
        recall_holds()
    assert "visibility_m" in str(exc.value) or "visibility_m" in "".join(
        getattr(exc.value, "__notes__", []))


@pytest.fixture(scope="session")
def haze_model():
    """fixtures/models/detector_haze.onnx: the same recipe with imaging-condition
    augmentation (make_detector.py train --haze-prob 0.5)."""
    return fa.ml.OnnxModel(scenarios.MODELS / "detector_haze.onnx", name="detector_haze")


def _kpis(model, frames):
    recs = [FrameRecord(i, t.objects, fa.ml.parse_detections(
                model(f), f.shape[:2], n_classes=2, where="det", score_threshold=0.05,
                input_hw=model.input_size), 25.0, 320, 240) for i, (f, t) in enumerate(frames)]
    return detection_kpis(recs, ("person", "vehicle"), score_threshold=0.4, min_visible=0.25)


def test_the_haze_augmented_detector_holds_in_haze_and_the_gate_shows_its_cost(
        fixed_views, det_model, haze_model):
    """In 300 m haze the shipped detector finds almost nothing and the augmented one
    keeps its recall budget; in clear air the augmented one is worse by more than
    the 5 % a baseline gate allows, so the gate catches the trade-off."""
    hazy = fixed_views.under(fa.Conditions(visibility_m=300.0), seed=1)
    with pytest.raises(AssertionError, match="recall"):
        check(_kpis(det_model, hazy), recall=">= 0.5")
    check(_kpis(haze_model, hazy), recall=">= 0.5")
    clear = {"flight": _kpis(haze_model, fixed_views.ideal())}
    shipped = {"flight": _kpis(det_model, fixed_views.ideal())}
    regressed = {d.kpi for d in compare({"t": shipped}, {"t": clear}, 5.0).regressions}
    assert "recall" in regressed


def test_detector_envelope_over_weather_shadows_and_rolling_shutter(fixed_views, det_model,
                                                                     tmp_path_factory):
    """The shipped detector (trained on clear, shadowless, global-shutter renders)
    against the flight's other conditions, written as a table: snow at any
    severity keeps recall >= 0.55 (0.70 in ideal light); rain breaks it from severity 1
    and water on the lens from severity 3; a low sun's shadows break it (each figure
    gets a dark twin), while its direction alone costs less; a 60 ms rolling-shutter
    readout at 16 m/s costs at most 0.12 (0.11: the skew is the ground's under the image
    centre for every view since one distance rule serves blur and skew; 0.08 when a view's
    skew followed a rooftop's depth)."""
    rows = []
    for weather in ("rain", "snow", "spatter"):
        for sev in range(1, 6):
            k = _kpis(det_model, fixed_views.under(fa.Conditions(weather=weather, severity=sev),
                                                   seed=1))
            rows.append((weather, sev, k["recall"]))
    recall = {(w, s): r for w, s, r in rows}
    out = os.environ.get("FLOCKAI_ENVELOPE_DIR") or tmp_path_factory.mktemp("weather")
    with open(os.path.join(out, "detector-weather.csv"), "w") as f:
        f.write("weather,severity,recall\n" + "".join(f"{w},{s},{r:.3f}\n" for w, s, r in rows))
    assert min(recall["snow", s] for s in range(1, 6)) >= 0.55
    assert max(recall["rain", s] for s in range(1, 6)) < 0.4
    assert recall["spatter", 1] >= 0.6 and max(recall["spatter", s] for s in range(3, 6)) < 0.3
    low_sun = dict(sun_azimuth_deg=250.0, sun_elevation_deg=25.0)
    lit = _kpis(det_model, fixed_views.under(fa.Conditions(**low_sun), seed=1))["recall"]
    shaded = _kpis(det_model, fixed_views.under(fa.Conditions(**low_sun, shadows=True),
                                                 seed=1))["recall"]
    assert lit >= 0.5 and shaded < 0.2
    ideal = _kpis(det_model, fixed_views.ideal())["recall"]
    skewed = _kpis(det_model, fixed_views.under(fa.Conditions(readout_s=0.06),
                                                velocity=(16.0, 0.0, 0.0), seed=1))["recall"]
    assert skewed >= ideal - 0.12
