"""uncoil from Python: load a scene, run it, get its samples as numpy arrays.

    import uncoil
    result = uncoil.run("yoga-mat", overrides={"push.contact_speed_m_s": 0.4})
    print(result.stop_reason, result.samples["r_m"][-1])

A scene is a shipped scene's name (`uncoil.scenes()` lists them, with their kinds) or the
path of a scene file, of either kind: a coil's, or the folded chain's (`"folded-chain"`).

The simulation is the Rust crate's (the extension module `uncoil._uncoil`); this layer only
turns what it returns into numpy arrays and dicts. A run writes files only when `out` is
given. It runs without the GIL, and Ctrl-C stops it with its files finished and raises
`KeyboardInterrupt`.
"""

from __future__ import annotations

import json
import math
import os
import re
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

import numpy as np

from . import _uncoil, theory
from ._uncoil import Scene, SceneError

__all__ = [
    "BANG_SHARES",
    "RunResult",
    "Scene",
    "SceneError",
    "ensemble",
    "load_scene",
    "run",
    "scenes",
    "sweep",
    "theory",
    "__version__",
]
__version__: str = _uncoil.__version__

PathLikeStr = Union[str, "os.PathLike[str]"]


def _toml_value(value: Any) -> str:
    """A Python value as the TOML text `uncoil run --set` takes."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    raise TypeError(f"an override must be a number, a bool or a string, not {type(value).__name__}")


#: An even range of values, `A..B/N`, as `uncoil sweep --vary` takes it.
_RANGE = re.compile(r"[^,:/]+\.\.[^,:/]+/[0-9]+")


def _setting(value: Any) -> str:
    """One setting of a varied key as `uncoil sweep --vary` takes it: a value, or for keys
    varied together (`a:b`) a tuple of theirs joined by `:`."""
    if isinstance(value, tuple):
        return ":".join(_toml_value(v) for v in value)
    return _toml_value(value)


def scenes() -> Dict[str, str]:
    """Every shipped scene, which `load_scene`, `run` and `sweep` take in place of a path, by
    name with its kind (`"coil"` or `"folded-chain"`): the scenes, then the hard cases
    (`"hard/thin-300"`, ...). The same list as `uncoil scenes` prints."""
    return dict(_uncoil.scenes())


def load_scene(path: PathLikeStr, overrides: Optional[Mapping[str, Any]] = None) -> Scene:
    """The scene in the TOML file at `path`, or the shipped scene of that name when no such
    file exists (`"yoga-mat"`, `"folded-chain"`: `scenes()` lists them), with `overrides`
    ({"solver.max_dt_s": 5e-4}) applied as `uncoil run --set` applies them. Either kind:
    `Scene.kind` says which.

    Raises `SceneError` with the command line's message when the scene is not valid.
    """
    pairs = [(key, _toml_value(value)) for key, value in (overrides or {}).items()]
    return _uncoil.load_scene(os.fspath(path), pairs)


class RunResult:
    """What a run gives: its samples by column, its report, and the report's main parts.

    A folded chain's run (`kind == "folded-chain"`) has the chain's columns and report, as
    `uncoil run folded-chain` writes them: its report's own part is `report["report"]`.
    """

    samples: Dict[str, np.ndarray]
    """Every column of `samples.csv`, as float64 arrays (NaN where the CSV cell is empty)."""
    report: Dict[str, Any]
    """`report.json` as a dict."""

    def __init__(self, samples: Dict[str, np.ndarray], report: Dict[str, Any]) -> None:
        self.samples = samples
        self.report = report

    @property
    def kind(self) -> str:
        """The scene's kind: `coil` or `folded-chain`."""
        return "folded-chain" if self.report.get("kind") == "folded-chain" else "coil"

    @property
    def stop_reason(self) -> str:
        """Why the run stopped: for a coil `at-rest`, `bang-cap`, `max-time`, `interrupted`, or
        a guard; for a folded chain `tip-fraction`, `rest`, `max-time`, `interrupted`, ..."""
        if self.kind == "folded-chain":
            return str(self.report["report"]["end"])
        return str(self.report["stop"]["reason"])

    @property
    def ledger(self) -> Dict[str, Any]:
        """The energy ledger (J): where the energy went (a folded chain's: by mechanism)."""
        if self.kind == "folded-chain":
            return dict(self.report["report"]["ledger"])
        return dict(self.report["ledger"])

    @property
    def milestones(self) -> List[Dict[str, Any]]:
        """A coil's milestones: radii reached, with the simulation's and the references' times;
        a folded chain's: the tip's crossings of x/L = 0.25-0.95 beside the closed form's."""
        if self.kind == "folded-chain":
            return list(self.report["report"]["crossings"])
        return list(self.report["milestones"])

    def to_pandas(self) -> Any:
        """The samples as a pandas DataFrame (needs pandas: `pip install "uncoil[pandas]"`,
        or `pip install ".[pandas]"` in the repository, or `pip install pandas`)."""
        try:
            import pandas as pd
        except ImportError as e:
            raise ModuleNotFoundError(
                "RunResult.to_pandas() needs pandas, which is not installed: "
                "pip install pandas (or install uncoil with its extra, "
                "pip install \".[pandas]\" in the repository)",
                name="pandas",
            ) from e

        return pd.DataFrame(self.samples)

    def __repr__(self) -> str:
        n = len(next(iter(self.samples.values()), []))
        return f"RunResult({self.report['scene']['name']!r}: {n} samples, stopped {self.stop_reason})"


def run(
    scene_or_path: Union[Scene, PathLikeStr],
    overrides: Optional[Mapping[str, Any]] = None,
    out: Optional[PathLikeStr] = None,
    mcap: bool = False,
) -> RunResult:
    """Runs a scene: a `Scene`, or a scene file's path or a shipped scene's name (`"yoga-mat"`,
    `"folded-chain"`) with `overrides`.

    Files (`samples.csv`, `report.json`, and for a coil `run.mcap` with `mcap=True`) are
    written only into `out`.
    """
    if isinstance(scene_or_path, Scene):
        if overrides:
            raise ValueError("overrides go with a scene path; load_scene applies them to a Scene")
        scene = scene_or_path
    else:
        scene = load_scene(scene_or_path, overrides)
    columns, report = _uncoil.run(scene, None if out is None else os.fspath(out), mcap)
    samples = {name: np.frombuffer(data, dtype="<f8") for name, data in columns}
    return RunResult(samples, json.loads(report))


def _column(cells: List[str]) -> Union[np.ndarray, List[str]]:
    """A sweep column: float64 (NaN for an empty cell) if every cell is a number, else text."""
    try:
        return np.array([float(c) if c else math.nan for c in cells], dtype=np.float64)
    except ValueError:
        return list(cells)


def sweep(
    scene: Union[Scene, PathLikeStr],
    vary: Mapping[str, Any],
    jobs: Optional[int] = None,
    out: Optional[PathLikeStr] = None,
) -> Dict[str, Union[np.ndarray, List[str]]]:
    """Runs `scene` (a coil's `Scene`, path or shipped name) over the product grid of `vary`
    ({"discretisation.links_per_turn": [16, 32]}, the last key varying fastest), `jobs` runs
    at once (default one per core), as `uncoil sweep` does, and gives `sweep.csv` by column:
    numbers as float64 arrays, the status as text. Files are written only into `out`.

    As on the command line, a key's values may be an even range written `"A..B/N"`
    ({"push.contact_speed_m_s": "0.300..0.307/8"}), and keys joined by `:` are varied
    together, each value a tuple of theirs ({"tape.thickness_m:solver.bang_piece_m":
    [(0.003, 0.015), (0.001, 0.005)]}).
    """
    header, rows = _sweep_table(scene, vary, jobs, out)
    return _columns(header, rows)


def _sweep_table(
    scene: Union[Scene, PathLikeStr],
    vary: Mapping[str, Any],
    jobs: Optional[int],
    out: Optional[PathLikeStr],
) -> Tuple[List[str], List[List[str]]]:
    """`sweep.csv`'s header and rows, as text."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    pairs = []
    for key, values in vary.items():
        if isinstance(values, str) and _RANGE.fullmatch(values.strip()):
            pairs.append((key, [values.strip()]))
            continue
        if isinstance(values, (str, bytes, tuple)) or not hasattr(values, "__iter__"):
            values = [values]
        pairs.append((key, [_setting(v) for v in values]))
    return _uncoil.sweep(scene, pairs, jobs, None if out is None else os.fspath(out))


def _columns(header: List[str], rows: List[List[str]]) -> Dict[str, Union[np.ndarray, List[str]]]:
    return {name: _column([row[k] for row in rows]) for k, name in enumerate(header)}


#: The bang's shares an ensemble pools (columns of `sweep.csv`, of what the bang dissipated),
#: each with the name the summary and the reports give its mechanism.
BANG_SHARES: Dict[str, str] = {
    "bang_floor_normal_of": "floor impacts",
    "bang_floor_friction_of": "floor friction",
    "bang_layers_normal_of": "layers' impacts",
    "bang_layers_friction_of": "layers' friction",
    "bang_freeze_of": "freezing",
    "bang_numerical_of": "numerical",
}


def ensemble(
    scene: PathLikeStr,
    n: int = 8,
    overrides: Optional[Mapping[str, Any]] = None,
    jobs: Optional[int] = None,
    out: Optional[PathLikeStr] = None,
) -> Dict[str, Any]:
    """Lands `scene` (a coil's scene file or shipped name, with `overrides`) from `n` pushes,
    its own and those just above it (a hundredth of the push's decade apart), as
    `uncoil run SCENE --ensemble N` does: a landing is chaotic.

    Gives {"runs": the sweep's table by column (as `sweep` gives it), "pooled": {column:
    (mean, standard error of the mean)} for each of `BANG_SHARES` over the runs that landed
    (ran to their end, their bang given time), "milestones": {label: (mean, standard
    deviation)} of the simulated time to each milestone (its `t_sim_<label>` column), the
    release and the bang's end (s) over the runs that ran to their end (their spread: the
    unrolls hardly differ), "n": how many landed}. The figures are the binary's own, as
    `ensemble.csv` holds them. Files are written only into `out`.
    """
    if not 2 <= n <= 1000:
        raise ValueError(f"n = {n}: the landings of an ensemble, from 2 to 1000")
    given = dict(overrides or {})
    push = json.loads(load_scene(scene, given).to_json())["push"]["contact_speed_m_s"]
    first, last = _uncoil.ensemble_pushes(push, n)
    vary: Dict[str, Any] = {k: [v] for k, v in given.items() if k != "push.contact_speed_m_s"}
    vary["push.contact_speed_m_s"] = f"{first}..{last}/{n}"
    header, rows = _sweep_table(scene, vary, jobs, out)
    # Pooled by the binary's own arithmetic, the figures `uncoil run --ensemble` prints.
    times, bang = _uncoil.pool(header, rows)
    pooled = {key: (mean, se) for key, _, mean, _, se, _, _ in bang if key in BANG_SHARES}
    milestones = {label: (mean, sd) for label, _, mean, sd, _, _, _ in times}
    landed = bang[0][1] if bang else 0
    return {"runs": _columns(header, rows), "pooled": pooled, "milestones": milestones, "n": landed}
