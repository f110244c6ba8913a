"""The Python package against the command line (independent reference: the CSV that
``host-sim run`` writes), and its errors. Run by scripts/python-test.sh in a fresh venv.

``ABSORBER_CLI`` is the host-sim binary (the script builds it); without it the tests that need
it call ``cargo run --release -p host-sim``.
"""

import csv
import json
import math
import os
import pathlib
import re
import shutil
import subprocess

import numpy as np
import pytest

import absorber

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cli(*args, cwd=None):
    exe = os.environ.get("ABSORBER_CLI")
    cmd = [exe] if exe else ["cargo", "run", "-q", "--release", "-p", "host-sim", "--"]
    done = subprocess.run(
        cmd + list(args), cwd=cwd or ROOT, capture_output=True, text=True, check=True
    )
    return done.stdout


@pytest.fixture(scope="module")
def paper_csv(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli")
    summary = json.loads(cli("run", "--scene", "paper", "--out", str(out), "--no-plots", "--json"))
    with open(out / "paper.csv") as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    return rows[0], rows[1:], summary["summary"]


@pytest.fixture(scope="module")
def paper_run():
    return absorber.run("paper")


def same_to_the_printed_digit(value: float, text: str) -> bool:
    """`text` is the CLI's `{:.9e}` (10 significant digits, round half to even on the exact
    binary value, as Python's `%.9e`): the value printed the same way must give the same digits."""
    if "e" not in text:
        return float(text) == value
    mant, exp = text.split("e")
    mine_mant, mine_exp = f"{value:.9e}".split("e")
    return mant == mine_mant and int(exp) == int(mine_exp)


def test_run_equals_the_cli_csv_of_the_paper_scene_to_the_last_printed_digit(paper_csv, paper_run):
    header, rows, _ = paper_csv
    assert list(absorber.CSV_COLUMNS) == header
    assert len(rows) == 20001  # 60 s / 3 ms + the initial row
    for j, name in enumerate(header):
        col = paper_run[name]
        assert col.dtype == np.float64 and col.shape == (len(rows),)
        bad = [i for i, r in enumerate(rows) if not same_to_the_printed_digit(float(col[i]), r[j])]
        assert not bad, f"{name}: row {bad[0]} CLI {rows[bad[0]][j]} Python {col[bad[0]]!r}"


def test_last_tip_deflection_prints_as_the_cli_last_row(paper_csv, paper_run):
    header, rows, _ = paper_csv
    last = paper_run["tip_deflection"][-1]
    assert f"{last:.9e}".replace("e-0", "e-") == rows[-1][header.index("tip_deflection")]
    # The paper scene's tip swings about its 16 mm static sag (README: -16.013 mm).
    assert -0.05 < last < 0.02


def test_run_summary_is_the_cli_summary(paper_csv, paper_run):
    _, _, summary = paper_csv
    assert paper_run["summary"] == summary
    # The README's sample output ("…; N stop impacts"): the same run, so the same count.
    shown = re.search(r"; (\d+) stop impacts", (ROOT / "README.md").read_text(encoding="utf-8"))
    assert shown, "README sample output"
    assert paper_run["summary"]["impacts"] == int(shown.group(1))


def test_static_and_modes_equal_the_cli():
    s = absorber.static("paper")
    assert s == json.loads(cli("static", "--json"))
    assert round(s["static_tip_deflection"] * 1e3, 3) == -16.013  # README
    f = absorber.modes("paper", count=3)
    assert list(f) == json.loads(cli("modes", "--count", "3", "--json"))["frequencies"]
    assert np.allclose(f, [2.355, 4.146, 40.850], atol=5e-4)  # README's lowest frequencies


def test_scene_from_a_toml_path_a_dict_and_overrides_are_the_same_scene(tmp_path):
    tuned = ROOT / "scenes" / "tuned.toml"
    a = absorber.static(tuned)
    b = absorber.static(str(tuned))
    assert a == b
    text = absorber.scene_toml("paper", elements=4, duration=2.0)
    path = tmp_path / "s.toml"
    path.write_text(text)
    from_file = absorber.run(path)
    from_dict = absorber.run({"elements": 4, "duration": 2.0})
    from_overrides = absorber.run("paper", elements=4, duration=2.0)
    for k in absorber.CSV_COLUMNS:
        np.testing.assert_array_equal(from_file[k], from_dict[k])
        np.testing.assert_array_equal(from_file[k], from_overrides[k])
    assert from_file["t"][-1] == pytest.approx(2.001, abs=1e-9)  # 667 steps of 3 ms


def test_sweep_equals_the_cli_sweep(tmp_path):
    freqs = [3.9, 4.13]
    s = absorber.sweep("paper", freqs, last=2.0, duration=6.0, jobs=2)
    out = json.loads(
        cli("sweep", "--freqs", "3.9,4.13", "--last", "2", "--duration", "6", "--out", str(tmp_path),
            "--no-plots", "--json")
    )
    assert [p["frequency"] for p in out["points"]] == list(s["frequency"])
    assert [p["tip_amplitude"] for p in out["points"]] == list(s["tip_amplitude"])
    assert [p["impacts"] for p in out["points"]] == list(s["impacts"])
    assert s["errors"] == [None, None]


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda: absorber.run({"beam": {"modulus": -200e9}}), "beam.modulus"),
        (lambda: absorber.static({"ball": {"track_radius": 0.005}}), "ball.track_radius"),
        (lambda: absorber.run("paper", step=-0.003), "integrator.step"),
        (lambda: absorber.modes({"integrator": {"gamma": 0.3}}), "integrator.gamma"),
        (lambda: absorber.run("paper", kind="pendulum"), "kind"),
        (lambda: absorber.run("paper", stiffness=1.0), "stiffness"),
        (lambda: absorber.run({"beam": {"length": "long"}}), "beam.length"),
        (lambda: absorber.sweep("paper", [4.0], last=100.0), "last"),
    ],
)
def test_a_bad_parameter_raises_with_the_name_of_its_field(call, field):
    with pytest.raises(absorber.AbsorberError) as e:
        call()
    assert e.value.field == field, str(e.value)
    assert isinstance(e.value, ValueError)


def test_a_missing_scene_file_raises_naming_it(tmp_path):
    with pytest.raises(absorber.AbsorberError, match="nope.toml"):
        absorber.run(str(tmp_path / "nope.toml"))


def test_run_doc_lists_every_output_column():
    # The docstring is checked against the command line's own column list.
    missing = [c for c in absorber.CSV_COLUMNS if f"``{c}``" not in absorber.run.__doc__]
    assert missing == [], missing
    assert "tip_acceleration" in absorber.CSV_COLUMNS


def test_messages_name_keyword_arguments_not_options():
    with pytest.raises(absorber.AbsorberError) as e:
        absorber.run("paper", duration=2.0, transient=5.0)
    assert "transient=" in str(e.value) and "--" not in str(e.value), str(e.value)
    assert e.value.field == "transient"


def test_sweep_returns_the_flight_fraction_over_the_window():
    # Default window: t >= outputs.transient (20 s), as run's summary.
    s = absorber.sweep("paper", [4.13], duration=24.0)
    r = absorber.run("paper", duration=24.0)
    c = r["summary"]["contact"]
    assert s["flight_fraction"][0] == pytest.approx(c["flight_fraction_steady"], abs=1e-3)
    assert s["tip_amplitude"][0] == r["summary"]["tip_amplitude_steady"]


def test_sweep_returns_the_locked_ball_the_cli_prints(tmp_path):
    s = absorber.sweep("paper", [4.0, 4.13], duration=24.0)
    cli("sweep", "--freqs", "4,4.13", "--duration", "24", "--out", str(tmp_path), "--no-plots")
    with open(tmp_path / "sweep.csv") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    # The CSV's locked column, to its printed digits (`{:.6e}`).
    assert [r["locked_tip_amplitude"] for r in rows] == [f"{x:.6e}".replace("e-0", "e-") for x in s["locked_tip_amplitude"]]
    # Independent: the scene run with the ball locked, over the same window (t >= 12 s).
    for f, locked in zip([4.0, 4.13], s["locked_tip_amplitude"]):
        r = absorber.run("paper", kind="locked", frequency=f, duration=24.0)
        assert locked == r["summary"]["tip_amplitude_steady"]
    # The passive absorber at 4.13 Hz: about twice the free ball's amplitude (32.7 vs 16.5 mm).
    assert s["locked_tip_amplitude"][1] > 1.5 * s["tip_amplitude"][1]
    # Without a free ball there is nothing to compare with: NaN, not the scene itself.
    t = absorber.sweep("paper", [4.13], duration=24.0, kind="locked")
    assert np.isnan(t["locked_tip_amplitude"]).all() and np.isnan(t["ball_max_deg"]).all()


def test_sweep_keys_and_doc_are_the_cli_sweep_columns(tmp_path):
    cli("sweep", "--freqs", "4.13", "--last", "2", "--duration", "6", "--out", str(tmp_path), "--no-plots")
    with open(tmp_path / "sweep.csv") as f:
        header = next(csv.reader(line for line in f if not line.startswith("#")))
    assert list(absorber.SWEEP_COLUMNS) == header
    numbers = [c for c in header if c not in ("status", "error")]
    s = absorber.sweep("paper", [4.13], last=2.0, duration=6.0)
    assert sorted(s) == sorted(numbers + ["errors"])
    e = absorber.sweep("paper", [4.13], last=2.0, duration=6.0, ensemble=2)
    assert sorted(e) == sorted(numbers + ["errors", "spread"])
    missing = [c for c in numbers if f"``{c}``" not in absorber.sweep.__doc__]
    assert missing == [], missing


def test_an_ensemble_prints_the_transient_note_once(capfd):
    # 4 s: the default 20 s transient falls back to the run's second half, with one note.
    note = "the default transient (20 s) would leave less than half of the run"
    absorber.run("paper", duration=4.0, ensemble=3)
    assert capfd.readouterr().err.count(note) == 1
    absorber.sweep("paper", [4.13], duration=4.0, ensemble=3)
    assert capfd.readouterr().err.count(note) == 1


def test_a_locked_ball_has_no_angle_of_its_own():
    r = absorber.run("paper", kind="locked", duration=4.0)
    s = r["summary"]
    assert s["ball"] == "locked" and s["ball_angle_max_deg"] is None
    for c in ("ball_angle", "ball_rel_angle", "ball_rate", "ball_spin"):
        assert np.isnan(r[c]).all(), c
    # It turns with the tip mass, which tip_angle gives (the static slope: about 4 degrees).
    assert 1.0 < abs(np.degrees(r["tip_angle"][0])) < 10.0
    assert absorber.run("paper", duration=4.0)["summary"]["ball"] == "free"
