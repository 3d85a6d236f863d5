"""The analytic references of a scene, as functions of a radius or a laid mass fraction.

Each takes a `Scene` (from `uncoil.load_scene`) and a number or an array, and gives a
number or a float64 array (NaN where the reference is not defined). The values are the
Rust crate's, the same a run compares itself with (`report.json`'s milestones and approach).

    scene = uncoil.load_scene("scenes/yoga-mat.toml")
    uncoil.theory.eq7_time_at_radius(scene, [0.045, 0.03])
"""

from __future__ import annotations

from typing import Sequence, Union, overload

import numpy as np

from . import _uncoil
from ._uncoil import Scene

__all__ = [
    "eq7_time_at_radius",
    "eq7_time_from_rest",
    "eq17_time_at_radius",
    "exact_time_at_fraction",
    "exact_speed_at_fraction",
]

ArrayLike = Union[Sequence[float], np.ndarray]


@overload
def _eval(scene: Scene, quantity: str, at: float) -> float: ...
@overload
def _eval(scene: Scene, quantity: str, at: ArrayLike) -> np.ndarray: ...
def _eval(scene, quantity, at):
    values = np.asarray(at, dtype=np.float64)
    out = np.array(_uncoil.theory(scene, quantity, values.ravel().tolist()), dtype=np.float64)
    return float(out[0]) if values.ndim == 0 else out.reshape(values.shape)


def eq7_time_at_radius(scene: Scene, r_m):
    """Time (s) at which eq. (7), with the corrected energy integral (ERRATA A1-A3), reaches
    radius `r_m` from the scene's push."""
    return _eval(scene, "eq7_time_at_radius", r_m)


def eq7_time_from_rest(scene: Scene, r_m):
    """Eq. (7)'s closed form from rest, for r >> b: `2 pi sqrt(R^3 - r^3) / (b sqrt(3 g))` (s)."""
    return _eval(scene, "eq7_time_from_rest", r_m)


def eq17_time_at_radius(scene: Scene, r_m):
    """Eq. (17)'s closed form (ERRATA C2): `3R / (13 |r0'|) (1 - (r/R)^(13/3))` (s)."""
    return _eval(scene, "eq17_time_at_radius", r_m)


def exact_time_at_fraction(scene: Scene, f):
    """Time (s) at which the exact-geometry model has laid the mass fraction `f`."""
    return _eval(scene, "exact_time_at_fraction", f)


def exact_speed_at_fraction(scene: Scene, f):
    """The exact-geometry model's contact-line speed (m/s) at the laid mass fraction `f`."""
    return _eval(scene, "exact_speed_at_fraction", f)
