"""Fleet-scale fatigue studies: task functions that run anywhere and results that add exactly.

A study of an arm design runs many wind records (10 minutes each, say) and adds up their
fatigue damage. The functions here are the units of work for a cluster (Dask, or any process
pool): module-level functions of plain data (a scene as a dict, TOML text or path; a seed; a
duration), picklable, that release the GIL while the model steps, and return plain data.

* :func:`simulate_record` returns the record's time histories as numpy arrays, its damage and
  its rainflow stress-range histogram.
* :func:`record_tally` returns only a :class:`DamageTally`: exact sums (``fractions.Fraction``)
  of the damage, its square and the simulated time, and integer half-cycle counts on fixed
  stress-range bins. Tallies add with ``+`` in any order and any grouping to the same result,
  bit for bit, so a tree reduction on a cluster equals the serial sum.

The record's model is the scene's ``[arm]`` under its ``[[loads]]`` (the buffeting's seeds
replaced by ones drawn from ``seed``), stepped by the embedded core; with ``absorber="free"``
the scene's ``[tip]`` housing and free ``[ball]`` sit at the arm's end, with ``"locked"`` the
same masses with the ball locked. ``examples/python/fleet_study.py`` is a whole study on
Dask; ``docs/fleet.md`` its measured throughput.

>>> from absorber import fleet
>>> t = fleet.record_tally("scenes/mast-arm.toml", seed=1, duration=30.0)  # doctest: +SKIP
>>> (t + t).damage == 2 * t.damage  # doctest: +SKIP
True
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Dict, Mapping, Optional, Tuple, Union

import numpy as np

from . import _absorber

__all__ = [
    "RANGE_BIN",
    "RANGE_EDGES",
    "SECONDS_PER_YEAR",
    "DamageTally",
    "frequencies",
    "record_tally",
    "simulate_record",
]

#: Width of a stress-range bin of the histograms [Pa].
RANGE_BIN: float = float(_absorber.FLEET_RANGE_BIN)
#: Edges of the stress-range bins [Pa]; the last bin also holds every larger range.
RANGE_EDGES: np.ndarray = np.arange(int(_absorber.FLEET_RANGE_BINS) + 1) * RANGE_BIN
#: Seconds of a (Julian) year.
SECONDS_PER_YEAR: float = 365.25 * 86400.0

#: A scene: a dict of scene keys, TOML text, a path or a built-in name.
SceneLike = Union[str, Mapping[str, Any]]


def _scene(scene: SceneLike) -> Any:
    return dict(scene) if isinstance(scene, Mapping) else str(scene)


def simulate_record(
    scene: SceneLike, seed: int, duration: float, absorber: str = "none", every: int = 10
) -> Dict[str, Any]:
    """Runs one wind record.

    Args:
        scene: a scene with an ``[arm]`` and ``[[loads]]`` (dict, TOML text, path).
        seed: the record's turbulence realization (replaces the buffeting seeds).
        duration: simulated time [s].
        absorber: ``"none"`` (the bare arm), ``"locked"`` or ``"free"`` (the scene's
            ``[tip]`` and ``[ball]`` at the arm's end).
        every: keep every n-th step in the time histories.

    Returns:
        ``time`` [s], ``root_stress`` [Pa], ``tip_deflection`` [m] (numpy arrays of the kept
        samples), ``histogram`` (int64 half-cycle counts per bin of :data:`RANGE_EDGES`) and
        ``summary``: ``damage`` (Miner, AASHTO S–N of ``arm.detail``, cycles below the
        constant-amplitude threshold doing none), ``damage_extended`` (the S–N line continued
        below it), ``max_range`` and ``stress_rms`` [Pa], ``tip_peak`` [m],
        ``static_stress`` [Pa], ``duration`` [s], ``steps``.

    Raises:
        AbsorberError: bad scene or argument (``field`` names it), or a step that failed.
    """
    names, arrays, summary, hist = _absorber.fleet_record(
        _scene(scene), int(seed), float(duration), absorber, int(every)
    )
    out: Dict[str, Any] = dict(zip(names, arrays))
    out["histogram"] = np.asarray(hist, dtype=np.int64)
    out["summary"] = json.loads(summary)
    return out


def frequencies(scene: SceneLike, absorber: str = "none") -> np.ndarray:
    """The reduced arm's natural frequencies [Hz], lowest first, with ``absorber`` (its ball
    free or locked) about the static equilibrium (to tune a track radius to half the first)."""
    return _absorber.fleet_frequencies(_scene(scene), absorber)


@dataclass
class DamageTally:
    """Damage of a set of records, as exact sums: adding tallies is exact, commutative and
    associative (``fractions.Fraction`` and integers), so any reduction order gives the same
    bits. ``damage`` uses the S–N curve with its threshold as a cutoff, ``damage_extended``
    the line continued below it."""

    records: int = 0
    seconds: Fraction = Fraction(0)
    damage: Fraction = Fraction(0)
    damage_squared: Fraction = Fraction(0)
    damage_extended: Fraction = Fraction(0)
    damage_extended_squared: Fraction = Fraction(0)
    histogram: np.ndarray = field(default_factory=lambda: np.zeros(len(RANGE_EDGES) - 1, dtype=np.int64))

    @classmethod
    def of_record(cls, summary: Mapping[str, Any], histogram: np.ndarray) -> "DamageTally":
        """The tally of one record (``simulate_record``'s ``summary`` and ``histogram``)."""
        d, e = Fraction(summary["damage"]), Fraction(summary["damage_extended"])
        return cls(1, Fraction(summary["duration"]), d, d * d, e, e * e, np.asarray(histogram, dtype=np.int64))

    def __add__(self, other: "DamageTally") -> "DamageTally":
        return DamageTally(
            self.records + other.records,
            self.seconds + other.seconds,
            self.damage + other.damage,
            self.damage_squared + other.damage_squared,
            self.damage_extended + other.damage_extended,
            self.damage_extended_squared + other.damage_extended_squared,
            self.histogram + other.histogram,
        )

    def __radd__(self, other: Any) -> "DamageTally":
        return self if other == 0 else NotImplemented  # sum(tallies) starts from 0

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, DamageTally)
            and (self.records, self.seconds, self.damage, self.damage_squared)
            == (other.records, other.seconds, other.damage, other.damage_squared)
            and (self.damage_extended, self.damage_extended_squared)
            == (other.damage_extended, other.damage_extended_squared)
            and np.array_equal(self.histogram, other.histogram)
        )

    def per_year(self, extended: bool = False, z: float = 1.96) -> Tuple[float, float, float]:
        """Damage per year [1/year] and its confidence interval ``(mean, low, high)``: the
        records are samples of the arm's climate (equal durations), the mean damage per record
        scaled to a year, ± ``z`` standard errors (1.96: 95 %, normal approximation of the
        mean; the low end at least 0)."""
        if self.records == 0 or self.seconds == 0:
            return (math.nan, math.nan, math.nan)
        n = self.records
        s, s2 = (self.damage_extended, self.damage_extended_squared) if extended else (self.damage, self.damage_squared)
        mean = s / n
        var = (s2 - n * mean * mean) / (n - 1) if n > 1 else Fraction(0)
        scale = SECONDS_PER_YEAR / float(self.seconds / n)
        half = z * math.sqrt(max(float(var), 0.0) / n)
        return (float(mean) * scale, max(float(mean) - half, 0.0) * scale, (float(mean) + half) * scale)

    def cycles(self) -> float:
        """Stress cycles counted (half cycles count ½)."""
        return int(self.histogram.sum()) / 2


def record_tally(scene: SceneLike, seed: int, duration: float, absorber: str = "none") -> DamageTally:
    """Runs one record (as :func:`simulate_record`) and returns only its :class:`DamageTally`:
    the task function of a study (a few kilobytes back from a worker)."""
    r = simulate_record(scene, seed, duration, absorber, every=1 << 62)
    return DamageTally.of_record(r["summary"], r["histogram"])
