"""Type stubs of the native module (the public, documented API is ``absorber``)."""

from typing import Any, Dict, List, Optional, Tuple

import numpy as np

CSV_COLUMNS: List[str]
SWEEP_COLUMNS: List[str]
BUILT_IN_SCENES: List[str]

class AbsorberError(ValueError):
    #: The scene key or option the error is about (e.g. ``"beam.modulus"``), if any.
    field: Optional[str]

def run(
    scene: Any,
    overrides: Optional[Dict[str, Any]] = None,
    transient: Optional[float] = None,
    every: Optional[int] = None,
    ensemble: int = 1,
    seed: int = 1,
) -> Tuple[List[str], List[np.ndarray], str, List[str]]: ...
def static_summary(scene: Any, overrides: Optional[Dict[str, Any]] = None) -> str: ...
def modes(scene: Any, overrides: Optional[Dict[str, Any]] = None, count: int = 4) -> np.ndarray: ...
def sweep(
    scene: Any,
    overrides: Optional[Dict[str, Any]] = None,
    freqs: Optional[List[float]] = None,
    last: Optional[float] = None,
    jobs: Optional[int] = None,
    ensemble: int = 1,
    seed: int = 1,
) -> str: ...
def scene_toml(scene: Any, overrides: Optional[Dict[str, Any]] = None) -> str: ...
