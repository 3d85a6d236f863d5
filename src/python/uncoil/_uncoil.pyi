"""Type stubs of the extension module built from src/python.rs."""

from os import PathLike
from typing import List, Optional, Tuple, Union

__version__: str

class SceneError(ValueError):
    """A scene file or an override that is not valid: the command line's `key = value: rule`."""

class Scene:
    @property
    def name(self) -> str: ...
    @property
    def kind(self) -> str: ...
    @property
    def source_text(self) -> str: ...
    def to_json(self) -> str: ...

def scenes() -> List[Tuple[str, str]]: ...
def load_scene(
    path: Union[str, PathLike[str]], overrides: List[Tuple[str, str]] = ...
) -> Scene: ...
def run(
    scene: Scene, out: Optional[Union[str, PathLike[str]]] = None, mcap: bool = False
) -> Tuple[List[Tuple[str, bytes]], str]: ...
def theory(scene: Scene, quantity: str, at: List[float]) -> List[float]: ...
def sweep(
    scene: Scene,
    vary: List[Tuple[str, List[str]]],
    jobs: Optional[int] = None,
    out: Optional[Union[str, PathLike[str]]] = None,
) -> Tuple[List[str], List[List[str]]]: ...
def pool(
    header: List[str], rows: List[List[str]]
) -> Tuple[
    List[Tuple[str, int, float, float, float, float, float]],
    List[Tuple[str, int, float, float, float, float, float]],
]: ...
def ensemble_pushes(v: float, n: int) -> Tuple[str, str]: ...
