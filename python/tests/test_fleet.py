"""Fleet studies: the task functions, exact tallies, and a small study on a Dask LocalCluster
with two workers whose merged damage equals the serial sum exactly."""

import importlib.util
import os
import pickle
from fractions import Fraction

import numpy as np
import pytest

import absorber
from absorber import fleet

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
ARM = os.path.join(ROOT, "scenes", "mast-arm.toml")


def study():
    spec = importlib.util.spec_from_file_location("fleet_study", os.path.join(ROOT, "examples", "python", "fleet_study.py"))
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


def test_record_is_plain_data_and_its_histogram_holds_its_cycles():
    r = fleet.simulate_record(ARM, seed=3, duration=30.0, every=5)
    assert r["time"].shape == r["root_stress"].shape == (601,)
    assert r["histogram"].dtype == np.int64 and r["histogram"].shape == (len(fleet.RANGE_EDGES) - 1,)
    s = r["summary"]
    assert s["steps"] == 3000 and s["damage_extended"] > 0.0
    # The largest range lies in the last occupied bin.
    last = np.flatnonzero(r["histogram"])[-1]
    assert fleet.RANGE_EDGES[last] <= s["max_range"] < fleet.RANGE_EDGES[last + 1] or last == len(r["histogram"]) - 1
    # Picklable in and out (what a cluster ships).
    assert pickle.loads(pickle.dumps(r))["summary"] == s
    assert pickle.loads(pickle.dumps(fleet.record_tally)) is fleet.record_tally


def test_tallies_add_exactly_in_any_order():
    ts = [fleet.record_tally(ARM, seed=k, duration=20.0) for k in range(6)]
    forward = sum(ts, fleet.DamageTally())
    backward = sum(reversed(ts), fleet.DamageTally())
    grouped = (ts[0] + ts[3]) + ((ts[5] + ts[1]) + (ts[2] + ts[4]))
    assert forward == backward == grouped
    assert forward.damage_extended == sum(Fraction(t.damage_extended) for t in ts)
    assert forward.records == 6 and forward.seconds == 120
    m, lo, hi = forward.per_year(extended=True)
    assert lo < m < hi


def test_scene_text_and_errors_name_the_field():
    text = open(ARM).read()
    a = fleet.record_tally(text, seed=1, duration=5.0)
    b = fleet.record_tally(ARM, seed=1, duration=5.0)
    assert a == b
    with pytest.raises(absorber.AbsorberError) as e:
        fleet.simulate_record(ARM, seed=1, duration=5.0, absorber="big")
    assert e.value.field == "absorber"
    with pytest.raises(absorber.AbsorberError) as e:
        fleet.simulate_record(ARM, seed=1, duration=-5.0)
    assert e.value.field == "duration"
    with pytest.raises(absorber.AbsorberError) as e:
        fleet.simulate_record("paper", seed=1, duration=5.0)
    assert "[arm]" in str(e.value)


def test_dask_study_on_two_workers_equals_the_serial_sum_exactly():
    s = study()
    work, _ = s.tasks(64, seed=11, duration=60.0)
    assert len(work) == 128
    serial = s.run_serial(work)
    distributed = s.run_dask(work, workers=2, quiet=True)
    assert distributed == serial  # every task, bit for bit
    a, b = s.summarize(serial, work), s.summarize(distributed, work)
    for k in ("none", "free"):
        assert a[k] == b[k]
        assert a[k].records == 64
        assert b[k].damage_extended == sum((t.damage_extended for t, w in zip(serial, work) if w[3] == k), Fraction(0))
    assert a["none"].damage_extended > 0
