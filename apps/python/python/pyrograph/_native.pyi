"""Type stubs for pyrograph's compiled module (re-exported by `pyrograph`)."""

import os
from typing import Any, Callable, Iterable, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Frames = Union[int, str, Iterable[int]]
"""A frame selection: an index, an iterable of indices (a range, a list) or a string in the CLI's
`--frames` grammar ("0-99", "0-99:2", "1,5,9-12"). Frames past the clip's end are an error."""

ProgressCallback = Callable[[dict], Any]
"""Called on the thread that called cook/render (never on a cooking thread), with one dict per
event as it arrives (in batches every ~20 ms): {"event": "node_started", "node"},
{"event": "node_finished", "node", "ok"} or {"event": "frame", "node", "done", "total"}. An
exception raised by the callback cancels the cook and propagates. The graph cannot be edited
from the callback (RuntimeError: already borrowed); reading it (get, nodes) is fine."""

Param = Union[bool, int, float, str, "os.PathLike[str]", Sequence[Any]]
Cooked = Union[
    npt.NDArray[np.float32],  # an image: H×W×C float32 (C = 1 gray, 4 RGBA), read-only
    npt.NDArray[np.uint8],  # a mask: H×W uint8 (0 or 255), read-only
    float,
    int,
    bool,
    str,
    "os.PathLike[str]",
    tuple,
    "Contours",
    "Value",
    "Clip",
    list,
]

class GraphError(Exception):
    """A graph that does not load, type-check or cook."""

    node: Optional[str]
    """The node at fault, or None."""
    port: Optional[str]
    """The port or parameter at fault, or None."""
    message: str
    """What went wrong (names the node and port)."""

class Problem:
    """One problem `Graph.check()` found."""

    file: Optional[str]
    node: Optional[str]
    port: Optional[str]
    location: str
    kind: str
    """Syntax, UnknownType, TypeMismatch, OutsideOutput, … or Cook for a source that failed."""
    message: str

class Graph:
    """A pyrograph graph with a persistent evaluator: a second cook re-uses every result whose
    inputs did not change."""

    def __init__(self, description: Optional[str] = None) -> None:
        """An empty graph; relative paths resolve against the current folder until it is saved."""
    @staticmethod
    def load(path: Union[str, os.PathLike[str]]) -> "Graph":
        """Reads a graph file (RON, any version; older versions are migrated)."""
    @staticmethod
    def from_ron(text: str, base_dir: Optional[Union[str, os.PathLike[str]]] = None) -> "Graph":
        """Parses RON text; relative paths resolve against base_dir (default: the current folder)."""
    def to_ron(self) -> str:
        """The document as RON, exactly what `save` writes."""
    def save(self, path: Union[str, os.PathLike[str]], overwrite: bool = False) -> None:
        """Writes atomically, byte for byte as `pyrograph save`; FileExistsError unless overwrite."""
    def check(self, out: Optional[Union[str, os.PathLike[str]]] = None, allow_outside_out: bool = False) -> list[Problem]:
        """Validates the graph and probes its sources, like `pyrograph check`; [] when fine."""
    @property
    def file(self) -> Optional[os.PathLike[str]]: ...
    @property
    def description(self) -> Optional[str]: ...
    @description.setter
    def description(self, text: Optional[str]) -> None: ...
    @property
    def nodes(self) -> dict[str, dict[str, Any]]:
        """Snapshot: id → {"type", "params", "pos"}."""
    @property
    def edges(self) -> list[tuple[str, str]]: ...
    @property
    def interface(self) -> Optional[dict[str, dict[str, str]]]:
        """For presets: {"inputs", "outputs", "params"} (name → inner port), else None."""
    @property
    def last_cooked(self) -> list[str]:
        """Node ids that actually cooked in the last cook or render (not served from the cache)."""
    @property
    def last_warnings(self) -> list[tuple[str, str]]:
        """(node, message) of every warning of the last cook or render (cached nodes do not repeat theirs)."""
    def add_node(self, id: str, type: str, **params: Param) -> None:
        """Adds a node of a registered type (see `nodes()`), with parameters as keywords."""
    def remove_node(self, id: str) -> None: ...
    def connect(self, src: str, dst: str) -> None:
        """Connects "node.output" to "node.input"; types are checked at check/cook time."""
    def disconnect(self, src: str, dst: str) -> None: ...
    def set(self, endpoint: str, value: Param) -> None:
        """Sets "node.param"; the next cook re-cooks only what depends on it. A string
        "keys([...])" or "expr(...)" animates it; in a point list, "face(3)" is a face."""
    def set_keys(self, endpoint: str, keys: Sequence[Tuple[Any, ...]], extrapolation: Optional[Union[str, Tuple[str, str]]] = None) -> None:
        """Keys "node.param": (frame, value) or (frame, value, interpolation) tuples."""
    def set_expr(self, endpoint: str, expression: str) -> None:
        """Sets "node.param" to an expression of frame, time and fps."""
    def get(self, endpoint: str) -> Any:
        """"node.param" as written, else its default."""
    def cook(self, endpoint: str, frames: Optional[Frames] = None, progress: Optional[ProgressCallback] = None) -> Cooked:
        """Cooks "node.port". Clips come back as a lazy `Clip`, or with `frames` as a list of
        frames. Releases the GIL; Ctrl-C cancels (KeyboardInterrupt)."""
    def render(
        self,
        out: Optional[Union[str, os.PathLike[str]]] = None,
        frames: Optional[Frames] = None,
        overwrite: bool = False,
        skip_existing: bool = False,
        nodes: Optional[list[str]] = None,
        allow_outside_out: bool = False,
        progress: Optional[ProgressCallback] = None,
    ) -> list[os.PathLike[str]]:
        """Runs the writers like `pyrograph render`; returns the render's files."""

class Clip:
    """A lazily cooked time-varying output: len(), clip[i], clip[a:b], clip.frames(sel)."""

    fps: float
    element: str
    def __len__(self) -> int: ...
    def __getitem__(self, index: Union[int, slice]) -> Any: ...
    def frames(self, selection: Frames, progress: Optional[ProgressCallback] = None) -> list[Any]: ...

class Contours:
    """Polygons traced from a mask; each item is {"points": N×2 float32, "depth", "parent", "area", "hole"}."""

    width: int
    height: int
    def __len__(self) -> int: ...
    def __getitem__(self, index: int) -> dict[str, Any]: ...

class Value:
    """A cooked value of a type a node crate declares (Mesh, Basis, FlameModel, …).

    Particles are not wrapped: they cook to a dict of numpy arrays, one row per particle —
    ``position`` and ``velocity`` (N×3), ``size`` (N×2), ``center`` and ``edge`` (N×4, straight
    RGBA), ``weight`` (N), ``group`` (N, uint32) — with the set's ``time``, ``sides`` and ``trails``."""

    type: str
    summary: str
    nbytes: int
    fingerprint: int

class FrameMemory:
    """The owner of cooked pixels that numpy arrays view (their `.base`)."""

def nodes() -> list[dict[str, Any]]:
    """Every node type with category, doc and ports: the same list as `pyrograph nodes --json`."""

def describe(type: str) -> str:
    """One node type's reference as Markdown (doc citing its paper section, ports, defaults,
    ranges): its section of docs/nodes.md. GraphError for an unknown type."""

def set_limits(
    *,
    read_roots: Sequence[str | os.PathLike[str]] | None = None,
    max_nodes: int | None = None,
    max_pixels: int | None = None,
    max_voxels: int | None = None,
) -> None:
    """Confine reads to `read_roots` (symbolic links followed; [] lifts it) and set the node,
    pixel and voxel limits (0 restores the default), process-wide, as the CLI's --read-root,
    --max-nodes, --max-pixels and --max-voxels. Arguments left out keep their setting."""

def limits() -> dict[str, Any]:
    """The limits in force: read_roots, max_nodes, max_pixels, max_voxels."""
