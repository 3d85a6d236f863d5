"""A typed use of the package, checked by `mypy --strict` in CI against the package's stubs:
if a stub and the package disagree in a way a user would meet, this fails to type-check."""

from __future__ import annotations

from typing import Dict, List

import numpy as np

import uncoil


def laid_fraction_at_the_end(name: str) -> float:
    result: uncoil.RunResult = uncoil.run(name, overrides={"discretisation.links_per_turn": 12})
    samples: Dict[str, np.ndarray] = result.samples
    return float(samples["laid_fraction"][-1])


def shipped() -> Dict[str, str]:
    return uncoil.scenes()


def kinds() -> List[str]:
    return [uncoil.load_scene(name).kind for name in ("yoga-mat", "folded-chain")]


def eq7_times(name: str) -> List[float]:
    scene: uncoil.Scene = uncoil.load_scene(name)
    one: float = uncoil.theory.eq7_time_at_radius(scene, 0.03)
    many: np.ndarray = uncoil.theory.exact_time_at_fraction(scene, [0.25, 0.5])
    return [one, *(float(v) for v in many)]


def bad_override() -> str:
    try:
        uncoil.load_scene("yoga-mat", {"tape.thickness_m": -1})
    except uncoil.SceneError as e:
        return str(e)
    return ""


if __name__ == "__main__":
    print(shipped(), kinds(), laid_fraction_at_the_end("yoga-mat"), eq7_times("yoga-mat"), bad_override())
