"""Free pendulum vibration absorber on a flexible beam, from Python.

The engine is the project's host tool (``host-sim``) compiled into this package: every function
here calls the same code as the matching command line (``run``, ``static``, ``modes``,
``sweep``), so the numbers are the command line's. SI units throughout (m, s, rad, J, Hz).

Scenes are given as

* a built-in name: ``"paper"`` (Table 1 of Gumus & Ertas: free ball, 3 elements, 0.5 mm at
  4.13 Hz, 60 s);
* a path to a scene TOML file (``str`` or ``pathlib.Path``), as ``scenes/*.toml``;
* a ``dict`` with the TOML file's keys, unset keys at the paper's values, e.g.
  ``{"ball": {"track_radius": 0.0488}, "duration": 30.0}``.

Keyword overrides are the command line's scene options: ``solver`` ("core" or "full"),
``kind`` ("beam", "tip", "locked", "free", "free-nostops"), ``elements``, ``precision``
("f32", "f64"), ``frequency`` [Hz], ``amplitude`` [m], ``duration`` [s], ``step`` [s].

Bad input raises :class:`AbsorberError` (a ``ValueError``) whose ``field`` attribute names the
scene key or option (``"beam.modulus"``, ``"integrator.step"``, ``"--last"``), never a crash.

>>> import absorber
>>> r = absorber.run("paper", duration=2.0)
>>> r["tip_deflection"].shape
(668,)
"""

from __future__ import annotations

import json
import os
import warnings
from typing import Any, Dict, Mapping, Optional, Sequence, Union

import numpy as np

from . import _absorber
from ._absorber import AbsorberError

__all__ = [
    "AbsorberError",
    "BUILT_IN_SCENES",
    "CSV_COLUMNS",
    "SWEEP_COLUMNS",
    "SceneLike",
    "modes",
    "run",
    "scene_toml",
    "static",
    "sweep",
]

AbsorberError.field = None  # the class default; set on each error that is about one field

#: A scene: a built-in name, a TOML file path, or a dict of scene keys.
SceneLike = Union[str, "os.PathLike[str]", Mapping[str, Any]]

#: Columns of :func:`run`'s result, in the order of the command line's CSV.
CSV_COLUMNS: tuple = tuple(_absorber.CSV_COLUMNS)

#: Columns of ``host-sim sweep``'s CSV, in order; :func:`sweep` returns one array per column
#: (``status`` and ``error`` become its ``"errors"`` list).
SWEEP_COLUMNS: tuple = tuple(_absorber.SWEEP_COLUMNS)

#: Names accepted as built-in scenes.
BUILT_IN_SCENES: tuple = tuple(_absorber.BUILT_IN_SCENES)


def _scene(scene: SceneLike) -> Any:
    return dict(scene) if isinstance(scene, Mapping) else scene


def _warn(messages: Sequence[str]) -> None:
    for m in messages:
        warnings.warn(m, RuntimeWarning, stacklevel=3)


def run(
    scene: SceneLike = "paper",
    *,
    transient: Optional[float] = None,
    every: Optional[int] = None,
    ensemble: int = 1,
    seed: int = 1,
    **overrides: Any,
) -> Dict[str, Any]:
    """Runs a scene in time, as ``host-sim run`` does, and returns its time histories.

    Args:
        scene: built-in name, TOML path or dict (see the module doc).
        transient: start of the steady-state window for the summary's amplitudes [s]
            (default: the scene's ``outputs.transient``, ``--transient``).
        every: keep every n-th step (default: the scene's ``outputs.every``, ``--every``).
        ensemble: runs from seeded perturbations of the ball's initial state (``--ensemble``):
            the time histories are member 0's (the scene itself), and every statistic of the
            summary is a dict ``{"mean", "sd", "min", "max", "k"}`` over the members.
        seed: seed of the perturbations (``--seed``).
        **overrides: ``solver``, ``kind``, ``elements``, ``precision``, ``frequency`` [Hz],
            ``amplitude`` [m], ``duration`` [s], ``step`` [s].

    Returns:
        A dict with one ``numpy.ndarray`` (float64) per CSV column of ``host-sim run``, keyed
        like the CSV header (:data:`CSV_COLUMNS`): ``t`` [s], ``base_y`` [m], ``tip_y`` [m],
        ``tip_deflection`` [m], ``tip_angle`` [rad], ``ball_angle`` [rad], ``ball_rel_angle``
        [rad], the energies ``beam_strain``, ``beam_kinetic``, ``beam_potential``,
        ``tip_kinetic``, ``tip_potential``, ``ball_kinetic``, ``ball_potential`` [J], ``iterations``,
        ``impact`` (0/1), ``base_accel`` [m/s²], ``tip_velocity`` [m/s], ``tip_rate``,
        ``ball_rate``, ``ball_rel_rate`` [rad/s], ``ball_spin`` [rad], ``ball_spin_rate``
        [rad/s], ``normal_force`` and ``tangential_force`` (the track's force on the ball) [N],
        ``contact`` (1 on the track, 0 in flight; NaN without a free ball),
        ``tip_acceleration`` (absolute, what a tip accelerometer reads) [m/s²]; and ``"summary"``: the dict ``host-sim run --json`` prints as ``summary``
        (static tip deflection, amplitudes, impacts, mean energies).

    Raises:
        AbsorberError: bad scene or option (``field`` names it), or a step that failed.
    """
    names, columns, summary, notes = _absorber.run(
        _scene(scene), overrides, transient, every, ensemble, seed
    )
    _warn(notes)
    out: Dict[str, Any] = dict(zip(names, columns))
    out["summary"] = json.loads(summary)
    return out


def static(scene: SceneLike = "paper", **overrides: Any) -> Dict[str, Any]:
    """Static equilibrium under gravity, as ``host-sim static --json``.

    Returns:
        ``{"scene", "kind", "elements", "solver", "static_tip_deflection"}``, the deflection of
        the beam end in m (negative: down).

    Raises:
        AbsorberError: bad scene or option, or a beam that cannot carry its load.
    """
    return json.loads(_absorber.static_summary(_scene(scene), overrides))


def modes(scene: SceneLike = "paper", count: int = 4, **overrides: Any) -> np.ndarray:
    """The ``count`` lowest natural frequencies [Hz] of the model linearized at its static
    equilibrium, as ``host-sim modes``.

    Raises:
        AbsorberError: bad scene or option.
    """
    if count < 1:
        raise AbsorberError(f"invalid value for `count`: {count} (must be at least 1)")
    return _absorber.modes(_scene(scene), overrides, count)


def sweep(
    scene: SceneLike = "paper",
    freqs: Optional[Sequence[float]] = None,
    *,
    last: Optional[float] = None,
    jobs: Optional[int] = None,
    ensemble: int = 1,
    seed: int = 1,
    **overrides: Any,
) -> Dict[str, Any]:
    """Frequency response, as ``host-sim sweep``: one run per excitation frequency, in parallel
    on ``jobs`` threads (default: all cores; the GIL is released), every figure over the steady
    window: the run after its transient (``outputs.transient``, 20 s; the window of :func:`run`),
    or the ``last`` seconds of each run.

    Args:
        scene: built-in name, TOML path or dict (must have a harmonic excitation).
        freqs: excitation frequencies [Hz] (default: the paper's 14, 3.50 … 4.70).
        last: steady-state window at the end of each run [s] (default: the run after
            ``outputs.transient``).
        jobs: worker threads.
        ensemble: runs per frequency from seeded perturbations of the ball's initial state
            (``--ensemble``): the arrays are then the means over the members (but
            ``locked_tip_amplitude``: one run, a locked ball has no initial angle to perturb),
            and ``"spread"`` holds, per statistic, arrays ``"sd"``, ``"min"``, ``"max"``, ``"k"``.
        seed: seed of the perturbations (``--seed``).
        **overrides: as for :func:`run` (``amplitude``, ``duration``, …).

    Returns:
        A dict of ``numpy.ndarray`` (one entry per frequency), one per column of ``host-sim
        sweep``'s CSV (:data:`SWEEP_COLUMNS`): ``frequency`` [Hz], ``tip_amplitude`` (half
        peak-to-peak) [m], ``tip_mean`` [m], ``ball_max_deg``, ``ball_amplitude_deg`` [deg]
        (NaN unless the ball is free), ``impacts``, ``flight_fraction`` (share of the window
        with the ball in flight) [-], ``max_iterations``, ``locked_tip_amplitude`` (the same
        run with the ball locked: the passive absorber the command's table and plot compare
        with, one run per frequency; NaN without a free ball or where that run failed) [m];
        and ``"errors"``: a list with ``None`` for a point that ran, else why it failed (its
        numbers are then NaN; a failed locked run is named there too).

    Raises:
        AbsorberError: bad scene, frequencies or window.
    """
    try:
        f = None if freqs is None else [float(x) for x in np.asarray(freqs, dtype=float).ravel()]
    except (TypeError, ValueError) as e:
        raise AbsorberError(
            f"invalid value for `freqs`: {freqs!r} (allowed: a sequence of numbers [Hz]; {e})"
        ) from None
    result = json.loads(_absorber.sweep(_scene(scene), overrides, f, last, jobs, ensemble, seed))
    points, locked = result["points"], result["locked"]
    columns = [c for c in SWEEP_COLUMNS if c not in ("status", "error", "locked_tip_amplitude")]
    counts = ("impacts", "max_iterations")
    keys = [c for c in columns if c not in counts]

    def number(p: Dict[str, Any], k: str, f: Optional[str] = None) -> float:
        if p["error"] or p[k] is None:
            return np.nan
        return p[k] if f is None else p[k][f]

    if ensemble > 1:
        stats = keys[1:] + list(counts)
        out: Dict[str, Any] = {
            k: np.array([number(p, k, "mean") for p in points], dtype=float) for k in stats
        }
        out["spread"] = {
            k: {
                f: np.array([number(p, k, f) for p in points], dtype=float)
                for f in ("sd", "min", "max", "k")
            }
            for k in stats
        }
    else:
        out = {k: np.array([number(p, k) for p in points], dtype=float) for k in keys}
        for k in counts:
            out[k] = np.array([p[k] for p in points], dtype=np.int64)
    out["frequency"] = np.array([p["frequency"] for p in points], dtype=float)
    out["locked_tip_amplitude"] = np.array(
        [number(locked[i], "tip_amplitude") if locked else np.nan for i in range(len(points))],
        dtype=float,
    )
    errors = [p["error"] for p in points]
    for i, l in enumerate(locked):
        if l["error"] and not errors[i]:
            errors[i] = f"locked ball: {l['error']}"
    out["errors"] = errors
    return out


def scene_toml(scene: SceneLike = "paper", **overrides: Any) -> str:
    """The scene, after the overrides, as the text of a scene TOML file (to save or inspect)."""
    return _absorber.scene_toml(_scene(scene), overrides)
