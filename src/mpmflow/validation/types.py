"""The types the validation cases share: what a case hands to a later one, a run's measures,
its meshes."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from .volume import Recorder

FloatArray = NDArray[np.float64]
# One run's measures by name (numbers, counts, arrays, tuples of arrays) that the case's
# rows, tables and figures read key by key: Any, as each key holds its own type.
Measures = dict[str, Any]


class Context(TypedDict, total=False):
    """What a case leaves for a later one: the volume measures recorded during the finest
    sloshing and dam-break runs, {flow: (run label, recorder)}."""

    volume: dict[str, tuple[str, Recorder]]


class Meshes(TypedDict):
    """A case's grid spacings (m) and run length (s)."""

    spacings: tuple[float, ...]
    end: float


class StepMeshes(Meshes):
    """Meshes with a time step (s) for each spacing: for a measure of a transient, whose
    error is the step's as well as the mesh's, so dt must be refined with h."""

    dts: tuple[float, ...]
