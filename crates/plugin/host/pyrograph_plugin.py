"""Declaring pyrograph node types in Python.

A plugin file is plain Python: each node type is a function decorated with `@node`, whose
parameter annotations are its input ports, whose defaults are the ports' defaults and whose return
annotation names its outputs::

    import numpy as np
    from pyrograph_plugin import node, Image, Float

    @node("studio.brighten", category="Studio", doc="Multiplies every sample by a gain.")
    def brighten(image: Image(doc="Frame to brighten"), gain: Float(range=(0.0, 8.0)) = 2.0) -> Image:
        return (image * gain).astype(np.float32)

A whole-clip node (time="whole_clip") sees a clip at once: a Clip input arrives as a ClipView
that fetches frames from pyrograph as they are indexed, and a Clip output is returned (or yielded)
frame by frame::

    @node("studio.reverse", time="whole_clip", doc="Plays a clip backwards.")
    def reverse(clip: Clip) -> Clip:
        for i in range(len(clip) - 1, -1, -1):
            yield clip[i]

The decorator returns the function unchanged, so it stays an ordinary function for tests and
scripts. Every declaration problem raises PluginDeclarationError when the file is executed, with
the function, the parameter and the file:line of the def in its message, so the editor can show a
broken plugin at load time rather than at its first cook.

This module imports nothing but the standard library: the worker imports it before it knows
whether numpy is installed, and it must be able to say so.
"""

import inspect
import linecache
import math
import numbers
import operator
import re
from dataclasses import dataclass
from typing import Callable, Dict, List, Optional

__all__ = [
    "node", "current_frame", "PluginDeclarationError", "NodeDeclaration", "ClipView", "FrameError",
    "Float", "Int", "Bool", "String", "Enum", "Color", "Vec2", "Vec3", "ColorRamp", "Curve", "Path", "Image", "Mask",
    "Clip", "Points",
    "Outputs",
]

TYPE_NAME = re.compile(r"[a-z][a-z0-9_]*(\.[a-z][a-z0-9_]*)+")
PORT_NAME = re.compile(r"[a-z][a-z0-9_]*")  # graph files name ports as node.port
TIMES = ("per_frame", "whole_clip")
CHANNELS = ("any", "gray", "rgba")


class PluginDeclarationError(Exception):
    """A @node declaration that cannot become a node type; the message says where and why."""


class _Problem(Exception):
    """A declaration problem before the function and parameter it belongs to are known."""


class FrameError(Exception):
    """pyrograph could not make a frame of a clip input, because a node upstream failed.

    ClipView raises it; let it propagate, and pyrograph reports the upstream node's own error."""


# Declarations made since the worker last took them: it executes a plugin file, then takes the
# nodes that file declared.
_declared: List["NodeDeclaration"] = []

# The frame being cooked, set by the worker around each call (None outside a cook, or when the
# graph cooks without a frame).
_frame: Optional[int] = None


def take_declared() -> List["NodeDeclaration"]:
    """The declarations made since the last call, forgetting them."""
    taken = list(_declared)
    _declared.clear()
    return taken


def current_frame() -> Optional[int]:
    """The frame the running cook is for, or None (outside a cook, or a cook without a frame).

    pyrograph does not send the frame to per-frame nodes: their result must depend only on their
    inputs, which is what their cache key holds, so for them this is None. A whole-clip node sees
    every frame at once, so for it this is None too."""
    return _frame


class ClipView:
    """A clip input of a whole-clip node: its frames, fetched from pyrograph as they are indexed.

    len(view) is the number of frames and view.fps their rate; view[i] is frame i as a read-only
    float32 array of shape (H,W) or (H,W,4) (a negative i counts from the end, like a list's), and
    `for frame in view` goes through them in order. Each view[i] fetches the frame again, so keep
    the frames you still need instead of indexing them twice, and only those: a long clip does not
    fit in memory at once. view[i] raises FrameError when pyrograph cannot make that frame.

    ClipView(frames, fps) wraps arrays you already have, to call the function in a test or script.
    """

    def __init__(self, frames, fps=24.0):
        frames = tuple(frames)
        self._length = len(frames)
        self._fps = float(fps)
        self._fetch = frames.__getitem__

    @classmethod
    def _fetching(cls, length, fps, fetch):
        """A view whose frame i is fetch(i), for 0 <= i < length (how the worker makes them)."""
        view = cls.__new__(cls)
        view._length, view._fps, view._fetch = length, float(fps), fetch
        return view

    def __len__(self):
        return self._length

    @property
    def fps(self) -> float:
        """Frames per second."""
        return self._fps

    def __getitem__(self, index):
        if isinstance(index, slice):
            raise TypeError("a clip is indexed one frame at a time: view[i], not a slice")
        i = operator.index(index)  # numpy integers too; floats and strings raise TypeError
        if i < 0:
            i += self._length
        if not 0 <= i < self._length:
            raise IndexError(f"frame {index} is outside the clip of {self._length} frames")
        return self._fetch(i)

    def __iter__(self):
        for i in range(self._length):
            yield self[i]

    def __repr__(self):
        return f"ClipView({self._length} frames at {self._fps:g} fps)"


# ---------------------------------------------------------------------------------------------
# Port kinds. The constructors only store their arguments: the checks run in the decorator, where
# an error can name the function and the parameter it belongs to.


class _Kind:
    """A port kind. Subclasses say which defaults they accept and what they add to the port."""

    kind = ""
    can_default = True
    options = ()
    channels = None

    def __init__(self, doc=""):
        self.doc = doc

    def _check(self):
        """Raises _Problem when the kind's own arguments are wrong."""
        if not isinstance(self.doc, str):
            raise _Problem(f"doc must be a str, got {type(self.doc).__name__}")

    def _default(self, value):
        """The JSON form of a Python default, or _Problem when the port cannot take it."""
        raise NotImplementedError

    def _range_json(self):
        return None

    def _port(self, name, default):
        return {
            "name": name,
            "kind": self.kind,
            "doc": " ".join(self.doc.split()),
            "default": default,
            "range": self._range_json(),
            "options": list(self.options),
            "channels": self.channels,
        }

    def __repr__(self):
        return f"{type(self).__name__}()"


def _is_number(value):
    """A finite real number that is not a bool (True is an int in Python, but not a number here)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def _is_integer(value):
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


class _Number(_Kind):
    """Float and Int: an optional inclusive range that the default must lie in."""

    noun = nouns = ""  # "a finite number" / "finite numbers", for messages

    def __init__(self, range=None, doc=""):
        super().__init__(doc)
        self.range = range

    # Set by the subclass: whether a value is of the kind, and its canonical Python form.
    _accepts: Callable[[object], bool]
    _convert: Callable[[object], object]

    def _check(self):
        super()._check()
        if self.range is None:
            return
        if not (isinstance(self.range, (tuple, list)) and len(self.range) == 2 and all(map(self._accepts, self.range))):
            raise _Problem(f"range must be (low, high) with two {self.nouns}, got {self.range!r}")
        low, high = self.range
        if low > high:
            raise _Problem(f"range ({low}, {high}) has its low end above its high end")

    def _range_json(self):
        return None if self.range is None else [self._convert(x) for x in self.range]

    def _default(self, value):
        if not self._accepts(value):
            raise _Problem(f"the default must be {self.noun}, got {value!r}")
        value = self._convert(value)
        if self.range is not None and not self.range[0] <= value <= self.range[1]:
            raise _Problem(f"the default {value} is outside the range {tuple(self._range_json())}")
        return value


class Float(_Number):
    """A float parameter, optionally limited to an inclusive range: Float(range=(0.0, 1.0))."""

    kind = "float"
    noun, nouns = "a finite number", "finite numbers"
    _accepts = staticmethod(_is_number)
    _convert = staticmethod(float)


class Int(_Number):
    """An integer parameter, optionally limited to an inclusive range: Int(range=(1, 16))."""

    kind = "int"
    noun, nouns = "an integer", "integers"
    _accepts = staticmethod(_is_integer)
    _convert = staticmethod(int)


class Bool(_Kind):
    """A checkbox."""

    kind = "bool"

    def _default(self, value):
        if not isinstance(value, bool):
            raise _Problem(f"the default of a Bool must be True or False, got {value!r}")
        return value


class String(_Kind):
    """A line of text."""

    kind = "string"

    def _default(self, value):
        if not isinstance(value, str):
            raise _Problem(f"the default of a String must be a str, got {value!r}")
        return value


class Enum(_Kind):
    """One of a fixed set of names: Enum("vertical", "horizontal"); the function gets the name."""

    kind = "enum"

    def __init__(self, *options, doc=""):
        super().__init__(doc)
        self.options = options

    def _check(self):
        super()._check()
        if not self.options:
            raise _Problem('an Enum needs its options: Enum("first", "second")')
        if not all(isinstance(o, str) and o for o in self.options):
            raise _Problem(f"Enum options must be non-empty strs, got {self.options!r}")
        if len(set(self.options)) != len(self.options):
            raise _Problem(f"Enum options must differ, got {self.options!r}")

    def _default(self, value):
        if not isinstance(value, str) or value not in self.options:
            raise _Problem(f"the default {value!r} is not one of the options {list(self.options)}")
        return value

    def __repr__(self):
        return f"Enum{self.options!r}"


class _Vector(_Kind):
    """Color, Vec2 and Vec3: a fixed number of floats; the function gets a tuple."""

    size = 0

    def _default(self, value):
        ok = isinstance(value, (tuple, list)) and len(value) == self.size and all(map(_is_number, value))
        if not ok:
            raise _Problem(f"the default of a {type(self).__name__} must be {self.size} finite numbers, got {value!r}")
        return [float(x) for x in value]


class Color(_Vector):
    """An RGBA colour: the function gets a tuple of 4 floats."""

    kind = "color"
    size = 4


class Vec2(_Vector):
    """Two floats (x, y)."""

    kind = "vec2"
    size = 2


class Vec3(_Vector):
    """Three floats (x, y, z)."""

    kind = "vec3"
    size = 3


class _Ramp(_Kind):
    """ColorRamp and Curve: keys over a position from 0 to 1, written as rows (position, values…)
    in position order; the function gets them as a read-only (K, 1 + width) float64 array."""

    width = 0

    def _default(self, value):
        size = 1 + self.width
        rows = list(value) if isinstance(value, (tuple, list)) else None
        ok = bool(rows) and all(
            isinstance(r, (tuple, list)) and len(r) == size and all(map(_is_number, r)) for r in rows
        )
        if not ok:
            raise _Problem(
                f"the default of a {type(self).__name__} must be keys of {size} finite numbers "
                f"(position, then {self.width} value{'s' if self.width > 1 else ''}), got {value!r}"
            )
        positions = [r[0] for r in rows]
        if positions != sorted(positions):
            raise _Problem(f"the keys of a {type(self).__name__} go in position order, got positions {positions}")
        return [[float(x) for x in r] for r in rows]


class ColorRamp(_Ramp):
    """A colour ramp: RGBA keys over a position, e.g. [(0.0, 0, 0, 0, 1), (1.0, 1, 0.8, 0.3, 1)]."""

    kind = "color_ramp"
    width = 4


class Curve(_Ramp):
    """A scalar curve: keys (position, value) over a position, e.g. [(0.0, 0.0), (1.0, 1.0)]."""

    kind = "curve"
    width = 1


class _Connection(_Kind):
    """A port whose value cannot be written in the declaration, so it has no default."""

    can_default = False


class Path(_Connection):
    """A file path; the function gets it as an absolute str."""

    kind = "path"


class Image(_Connection):
    """An image: a read-only float32 array of shape (H,W) (gray) or (H,W,4) (RGBA).

    channels="gray" or "rgba" restricts what an output may return; "any" takes both.
    """

    kind = "image"

    def __init__(self, channels="any", doc=""):
        super().__init__(doc)
        self.channels = channels

    def _check(self):
        super()._check()
        if self.channels not in CHANNELS:
            raise _Problem(f"channels must be one of {', '.join(map(repr, CHANNELS))}, got {self.channels!r}")


class Mask(_Connection):
    """A mask: a read-only uint8 array of shape (H,W); an output may also be a bool array."""

    kind = "mask"


class Clip(_Connection):
    """A clip of images, for whole-clip nodes. An input arrives as a ClipView; an output is the
    frames, returned as a generator (or yielded), a list or tuple of float32 arrays of one shape,
    or one float32 array of shape (N,H,W) or (N,H,W,4). Clip(Image) says the same as Clip.
    """

    kind = "clip"

    def __init__(self, of=Image, doc=""):
        super().__init__(doc)
        self.of = of

    def _check(self):
        super()._check()
        of = self.of
        if isinstance(of, str):
            raise _Problem(f"Clip takes the kind of its frames, Image; give the doc as Clip(doc={of!r})")
        # A clip's frames may be gray or RGBA (pyrograph does not say which before it cooks), so
        # an Image that insists on channels is refused rather than silently ignored.
        if not (of is Image or (type(of) is Image and of.channels == "any")):
            raise _Problem(f"a Clip holds images of any channels: Clip or Clip(Image), not Clip({of!r})")


class Points(_Connection):
    """Emitter points, as an output: a numpy array of shape (N,3) holding x,y,z (emitting from
    time 0) or (N,4) holding seconds,x,y,z, for volume.source's point list."""

    kind = "points"


# What a function may return, and the name a single output of that kind takes.
_SINGLE_OUTPUT = {
    Image: "image", Mask: "mask", Clip: "clip", Points: "points", Float: "value", Int: "value", Bool: "value",
}


class Outputs:
    """Several outputs, in keyword order: -> Outputs(image=Image(), mask=Mask()).

    The function then returns a dict with exactly these keys, or a tuple in this order.
    """

    def __init__(self, **ports):
        self.ports = ports

    def _kinds(self) -> Dict[str, _Kind]:
        if not self.ports:
            raise _Problem("Outputs needs at least one output: Outputs(image=Image(), mask=Mask())")
        kinds = {}
        for name, kind in self.ports.items():
            try:
                _check_port_name(name)
                kinds[name] = _output_kind(kind)
            except _Problem as problem:
                raise _Problem(f"output '{name}': {problem}") from None
        return kinds

    def __repr__(self):
        return f"Outputs({', '.join(self.ports)})"


def _check_port_name(name):
    if not PORT_NAME.fullmatch(name):
        raise _Problem(f"the port name {name!r} must be lower-case letters, digits and '_', starting with a letter")


def _output_kind(kind) -> _Kind:
    """The checked kind of one output, given as a class or an instance."""
    if isinstance(kind, type) and issubclass(kind, _Kind):
        kind = kind()
    if type(kind) not in _SINGLE_OUTPUT:
        raise _Problem(
            f"{kind!r} cannot be an output (outputs are Image, Mask, Clip, Points, Float, Int or Bool; "
            "several go in Outputs(...))"
        )
    kind._check()
    return kind


# ---------------------------------------------------------------------------------------------
# The decorator.


@dataclass
class NodeDeclaration:
    """What @node attached to a function (as fn.__pyrograph__): the node type it declares."""

    type_name: str
    category: str
    doc: str
    time: str
    function: Callable
    file: str
    line: int
    inputs: List[dict]
    outputs: List[dict]
    # True when the return annotation is Outputs(...): the function returns a dict or a tuple.
    several_outputs: bool

    def as_dict(self) -> dict:
        """The declaration the worker sends to pyrograph (JSON-ready)."""
        return {
            "type_name": self.type_name,
            "category": self.category,
            "doc": self.doc,
            "time": self.time,
            "function": self.function.__name__,
            "line": self.line,
            "inputs": [dict(p) for p in self.inputs],
            "outputs": [dict(p) for p in self.outputs],
        }


def node(type_name, *, category="Plugins", time="per_frame", doc=None):
    """Declares the decorated function as the node type `type_name` ("studio.heat_haze").

    category is the editor's palette section; doc is the one-line summary (by default the first
    paragraph of the docstring); time says when the node cooks: "per_frame" (once per frame of
    the clips wired in, which pyrograph does itself) or "whole_clip" (once, seeing whole clips:
    the only kind of node that may have Clip inputs or outputs). Returns the function itself.
    """
    if inspect.isfunction(type_name):
        # @node without parentheses passes the function as the type name.
        where = _where(type_name, _def_line(type_name))
        raise PluginDeclarationError(f"{where}: @node needs a type name: @node(\"studio.my_node\")")

    def declare(function):
        declaration = _declare(function, type_name, category, time, doc)
        function.__pyrograph__ = declaration
        _declared.append(declaration)
        return function

    return declare


_DEF = re.compile(r"\s*(async\s+)?def\s")


def _def_line(function) -> int:
    """The line of the `def` itself: co_firstlineno is the first decorator's line."""
    code = function.__code__
    lines = linecache.getlines(code.co_filename, function.__globals__)
    for number in range(code.co_firstlineno, len(lines) + 1):
        if _DEF.match(lines[number - 1]):
            return number
    return code.co_firstlineno


def _where(function, line) -> str:
    return f"{function.__code__.co_filename}:{line}: function '{function.__name__}'"


def _declare(function, type_name, category, time, doc) -> NodeDeclaration:
    if not inspect.isfunction(function):
        raise PluginDeclarationError(f"@node({type_name!r}) decorates a function, not {function!r}")
    line = _def_line(function)
    where = _where(function, line)

    def fail(problem):
        return PluginDeclarationError(f"{where}: {problem}")

    if not isinstance(type_name, str) or not TYPE_NAME.fullmatch(type_name):
        raise fail(f"the type name {type_name!r} must be namespaced lowercase words like 'studio.heat_haze'")
    if time not in TIMES:
        raise fail(f"time={time!r} is not supported; this version supports {', '.join(map(repr, TIMES))}")
    if not isinstance(category, str) or not category.strip():
        raise fail(f"category must be a non-empty str, got {category!r}")
    if doc is not None and not isinstance(doc, str):
        raise fail(f"doc must be a str, got {type(doc).__name__}")
    summary = " ".join((doc if doc is not None else _first_paragraph(function.__doc__)).split())
    if not summary:
        raise fail("a node needs a doc line: a docstring or doc=\"...\"")

    signature = inspect.signature(function)
    inputs = []
    for parameter in signature.parameters.values():
        try:
            inputs.append(_input(parameter, function.__globals__))
        except _Problem as problem:
            raise fail(f"parameter '{parameter.name}': {problem}") from None
    try:
        outputs, several = _outputs(signature.return_annotation, function.__globals__)
    except _Problem as problem:
        raise fail(f"return annotation: {problem}") from None
    if time != "whole_clip":
        clips = [f"parameter '{p['name']}'" for p in inputs if p["kind"] == "clip"]
        clips += [f"return annotation: output '{p['name']}'" for p in outputs if p["kind"] == "clip"]
        if clips:
            raise fail(
                f"{clips[0]}: a Clip needs @node(..., time=\"whole_clip\"); a per-frame node takes and "
                "returns an Image, and pyrograph applies it to every frame of a clip by itself"
            )

    return NodeDeclaration(
        type_name=type_name, category=category, doc=summary, time=time, function=function,
        file=function.__code__.co_filename, line=line,
        inputs=inputs, outputs=outputs, several_outputs=several,
    )


def _first_paragraph(docstring) -> str:
    if not docstring:
        return ""
    return inspect.cleandoc(docstring).split("\n\n")[0]


def _kind(annotation, namespace):
    """The port kind an annotation names: a kind class, an instance, or either as a string."""
    if isinstance(annotation, str):
        # `from __future__ import annotations` leaves every annotation as source text.
        try:
            annotation = eval(annotation, namespace)
        except Exception as error:
            raise _Problem(f"cannot evaluate the annotation {annotation!r}: {type(error).__name__}: {error}") from None
    if isinstance(annotation, type) and issubclass(annotation, (_Kind, Outputs)):
        annotation = annotation()
    if not isinstance(annotation, (_Kind, Outputs)):
        raise _Problem(
            f"the annotation {annotation!r} is not a port kind "
            "(Float, Int, Bool, String, Enum, Color, Vec2, Vec3, ColorRamp, Curve, Path, Image, Mask, Clip, Points)"
        )
    return annotation


_PARAMETER_PROBLEMS = {
    inspect.Parameter.VAR_POSITIONAL: "*args cannot be a port; declare each input as its own parameter",
    inspect.Parameter.VAR_KEYWORD: "**kwargs cannot be a port; declare each input as its own parameter",
    inspect.Parameter.POSITIONAL_ONLY: "a positional-only parameter cannot be a port (inputs are passed by name)",
}


def _input(parameter, namespace) -> dict:
    """The port dict of one parameter."""
    if parameter.kind in _PARAMETER_PROBLEMS:
        raise _Problem(_PARAMETER_PROBLEMS[parameter.kind])
    _check_port_name(parameter.name)
    if parameter.annotation is inspect.Parameter.empty:
        raise _Problem("needs a port annotation, such as Float(range=(0.0, 1.0)) or Image")
    kind = _kind(parameter.annotation, namespace)
    if isinstance(kind, Outputs):
        raise _Problem("Outputs(...) is for the return annotation")
    if isinstance(kind, Points):
        raise _Problem("Points inputs are not supported yet; Points can only be an output")
    kind._check()
    if parameter.default is inspect.Parameter.empty:
        return kind._port(parameter.name, None)
    if not kind.can_default:
        raise _Problem(f"a {type(kind).__name__} input cannot have a default")
    return kind._port(parameter.name, kind._default(parameter.default))


def _outputs(annotation, namespace):
    """The output port dicts of a return annotation, and whether there are several."""
    if annotation is inspect.Signature.empty:
        raise _Problem("missing; say what the node returns: -> Image, Mask, Clip, Points, Float, Int, Bool or Outputs(...)")
    kind = _kind(annotation, namespace)
    if isinstance(kind, Outputs):
        return [k._port(name, None) for name, k in kind._kinds().items()], True
    kind = _output_kind(kind)
    return [kind._port(_SINGLE_OUTPUT[type(kind)], None)], False
