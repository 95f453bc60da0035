"""Inference latency percentiles kept as the inferences finish (``ml.metrics.SortedValues``):
the same numbers as NumPy's ``percentile`` bit for bit, whatever the order values arrive in,
so the probes can read them every sample without recomputing over the whole flight."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pytest_flockai.ml.metrics import SortedValues, percentile

LATENCIES = st.lists(st.floats(min_value=0.0, max_value=1e4, allow_nan=False), min_size=1,
                     max_size=300)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(values=LATENCIES, q=st.one_of(st.sampled_from([0.0, 5.0, 50.0, 95.0, 99.0, 100.0]),
                                     st.floats(min_value=0.0, max_value=100.0)))
def test_running_percentiles_equal_numpys_bit_for_bit(values, q):
    s = SortedValues()
    for i, v in enumerate(values):
        s.add(v)
        seen = values[: i + 1]
        assert s.percentile(q) == percentile(seen, q) == float(np.percentile(seen, q))
        assert s.max() == max(seen) and len(s) == i + 1


def test_an_empty_record_gives_nan():
    s = SortedValues()
    assert math.isnan(s.percentile(50)) and math.isnan(s.max()) and len(s) == 0


def test_ties_and_a_long_flight_of_inferences():
    rng = np.random.default_rng(7)
    values = list(np.round(rng.gamma(2.0, 0.05, 9000), 3))      # 30 min at 5 Hz, many ties
    s = SortedValues()
    for v in values:
        s.add(v)
    for q in (50, 95, 99.9):
        assert s.percentile(q) == float(np.percentile(values, q))
