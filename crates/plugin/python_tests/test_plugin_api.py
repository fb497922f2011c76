"""The declaration API (pyrograph_plugin): what @node makes of a function, and every way a
declaration is refused, with the place of the def in the message."""

import importlib.util
import json
import pathlib
import sys
import textwrap

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
HOST_DIR = ROOT / "crates" / "plugin" / "host"
HEAT_HAZE = ROOT / "examples" / "plugins" / "heat_haze" / "plugins" / "heat_haze.py"
sys.path.insert(0, str(HOST_DIR))

import pyrograph_plugin  # noqa: E402  (found through HOST_DIR, as the worker's PYTHONPATH finds it)
from pyrograph_plugin import PluginDeclarationError  # noqa: E402


def load(path, name=None):
    """Executes a plugin file as a module, as a test or a script would import it."""
    spec = importlib.util.spec_from_file_location(name or f"plugin_{pathlib.Path(path).stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def def_line(path, text):
    """The number of the first line of the file that holds `text`."""
    return next(i for i, line in enumerate(pathlib.Path(path).read_text().splitlines(), 1) if text in line)


def write(tmp_path, source, name="plugin.py"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(source))
    return path


@pytest.fixture(scope="module")
def heat_haze():
    return load(HEAT_HAZE).heat_haze


def port(name, kind, doc="", default=None, range=None, options=(), channels=None):
    return {"name": name, "kind": kind, "doc": doc, "default": default, "range": range,
            "options": list(options), "channels": channels}


def test_the_decorator_returns_the_function_itself(heat_haze):
    assert callable(heat_haze) and heat_haze.__name__ == "heat_haze"
    assert heat_haze.__pyrograph__.function is heat_haze
    rgba = np.random.default_rng(1).random((6, 9, 4), dtype=np.float32)
    out = heat_haze(rgba, amount=3.0, wavelength=5.0)
    assert out.dtype == np.float32 and out.shape == rgba.shape
    assert not np.array_equal(out, rgba)
    # Amount 0 moves nothing, on gray and RGBA frames and along both axes.
    for image in (rgba, rgba[..., 0]):
        for axis in ("vertical", "horizontal"):
            same = heat_haze(image, amount=0.0, axis=axis)
            assert same.dtype == np.float32 and np.array_equal(same, image)


def test_heat_haze_shifts_rows_by_interpolated_subpixel_amounts(heat_haze):
    ramp = np.tile(np.arange(8, dtype=np.float32), (4, 1))  # each row 0, 1, ..., 7
    out = heat_haze(ramp, amount=0.25, wavelength=4.0)  # rows shift by 0.25·sin(πy/2): 0, ¼, 0, −¼
    np.testing.assert_allclose(out[0], ramp[0], atol=1e-6)
    # Row 1 moves right by a quarter pixel: each sample is ¾ of itself and ¼ of its left
    # neighbour, and the first repeats the edge.
    np.testing.assert_allclose(out[1], [0, 0.75, 1.75, 2.75, 3.75, 4.75, 5.75, 6.75], atol=1e-6)
    np.testing.assert_allclose(out[2], ramp[2], atol=1e-6)
    np.testing.assert_allclose(out[3], [0.25, 1.25, 2.25, 3.25, 4.25, 5.25, 6.25, 7], atol=1e-6)
    # Horizontal waves are the same shift applied to the columns; RGBA shifts every channel alike.
    np.testing.assert_array_equal(heat_haze(ramp.T.copy(), amount=0.25, wavelength=4.0, axis="horizontal"), out.T)
    rgba = np.stack([ramp, 2 * ramp, ramp + 1, np.ones_like(ramp)], axis=-1)
    shifted = heat_haze(rgba, amount=0.25, wavelength=4.0)
    np.testing.assert_allclose(shifted[..., 1], 2 * out, atol=1e-6)
    np.testing.assert_allclose(shifted[..., 3], 1, atol=1e-6)


def test_heat_haze_declaration(heat_haze):
    assert heat_haze.__pyrograph__.as_dict() == {
        "type_name": "studio.heat_haze",
        "category": "Studio",
        "doc": "Shimmers a frame with sine displacement, like air above a flame.",
        "time": "per_frame",
        "function": "heat_haze",
        "line": def_line(HEAT_HAZE, "def heat_haze("),
        "inputs": [
            port("image", "image", "Frame to distort", channels="any"),
            port("amount", "float", "Displacement in pixels", 4.0, [0.0, 20.0]),
            port("wavelength", "float", "Wave length in pixels", 40.0, [2.0, 400.0]),
            port("axis", "enum", "Direction of the waves", "vertical", options=["vertical", "horizontal"]),
        ],
        "outputs": [port("image", "image", channels="any")],
    }


KINDS_SOURCE = """
    from pyrograph_plugin import node, Bool, Color, Enum, Float, Image, Int, Mask, Outputs, Path, String, Vec2, Vec3

    LIMITS = (1, 3)

    @node("test.kinds", category="Tests", doc="  Every   kind\\n of port. ")
    def kinds(
        count: Int(range=LIMITS, doc="How many"),
        source: Path,
        mask: Mask(doc="Where"),
        gray: Image(channels="gray"),
        gain: Float = 2,
        on: Bool = True,
        label: String = "x",
        mode: Enum("a", "b") = "b",
        tint: Color = (1, 0.5, 0, 1),
        at: Vec2 = [0, 1],
        *,
        up: Vec3(doc="Up") = (0.0, 0.0, 1.0),
    ) -> Outputs(image=Image(channels="rgba"), matte=Mask, total=Float(doc="Sum")):
        return {}
"""

KINDS_DECLARATION = {
    "type_name": "test.kinds",
    "category": "Tests",
    "doc": "Every kind of port.",
    "time": "per_frame",
    "function": "kinds",
    "inputs": [
        port("count", "int", "How many", range=[1, 3]),
        port("source", "path"),
        port("mask", "mask", "Where"),
        port("gray", "image", channels="gray"),
        port("gain", "float", default=2.0),
        port("on", "bool", default=True),
        port("label", "string", default="x"),
        port("mode", "enum", default="b", options=["a", "b"]),
        port("tint", "color", default=[1.0, 0.5, 0.0, 1.0]),
        port("at", "vec2", default=[0.0, 1.0]),
        port("up", "vec3", "Up", default=[0.0, 0.0, 1.0]),
    ],
    "outputs": [
        port("image", "image", channels="rgba"),
        port("matte", "mask"),
        port("total", "float", "Sum"),
    ],
}


@pytest.mark.parametrize("future", [False, True], ids=["annotations", "string_annotations"])
def test_every_kind_of_port_and_string_annotations(tmp_path, future):
    source = textwrap.dedent(KINDS_SOURCE)
    if future:
        source = "from __future__ import annotations\n" + source
    path = write(tmp_path, source)
    declaration = load(path, f"kinds_{future}").kinds.__pyrograph__
    if future:
        assert isinstance(declaration.function.__annotations__["count"], str)  # really strings
    assert declaration.several_outputs
    expected = dict(KINDS_DECLARATION, line=def_line(path, "def kinds("))
    assert declaration.as_dict() == expected
    # As JSON too, where 2 and 2.0 differ: a Float's default and range are floats, an Int's ints.
    assert json.dumps(declaration.as_dict(), sort_keys=True) == json.dumps(expected, sort_keys=True)
    assert declaration.file == str(path)


def test_single_outputs_are_named_after_their_kind(tmp_path):
    path = write(tmp_path, """
        from pyrograph_plugin import node, Bool, Float, Image, Int, Mask

        @node("test.a", doc="A")
        def a() -> Mask: ...

        @node("test.b", doc="B")
        def b() -> Float: ...

        @node("test.c", doc="C")
        def c() -> Int(doc="Count"): ...

        @node("test.d", doc="D")
        def d() -> Bool: ...
    """)
    module = load(path)
    outputs = [f.__pyrograph__.as_dict()["outputs"] for f in (module.a, module.b, module.c, module.d)]
    assert outputs == [[port("mask", "mask")], [port("value", "float")], [port("value", "int", "Count")], [port("value", "bool")]]
    assert module.a.__pyrograph__.as_dict()["category"] == "Plugins"


def test_the_worker_takes_the_declarations_of_a_file(tmp_path):
    pyrograph_plugin.take_declared()
    path = write(tmp_path, """
        from pyrograph_plugin import node, Float

        @node("test.one", doc="One")
        def one() -> Float: ...

        @node("test.two", doc="Two")
        def two() -> Float: ...
    """)
    load(path)
    assert [d.type_name for d in pyrograph_plugin.take_declared()] == ["test.one", "test.two"]
    assert pyrograph_plugin.take_declared() == []


# Each class of declaration error: the function's parameters and return annotation, the @node
# arguments, and words the message must hold besides the function, the parameter and file:line.
ERRORS = {
    "type_name_not_namespaced": ('"heat_haze"', "x: Float = 1.0", "-> Image", None, "namespaced"),
    "type_name_uppercase": ('"Studio.Haze"', "x: Float = 1.0", "-> Image", None, "namespaced"),
    "unsupported_time": ('"test.f", time="per_step"', "x: Float = 1.0", "-> Image", None, "'per_frame', 'whole_clip'"),
    "no_doc": ('"test.f", doc=None', "x: Float = 1.0", "-> Image", None, "doc line"),
    "parameter_name_not_lower_case": ('"test.f"', "Gain: Float = 1.0", "-> Image", "Gain", "lower-case"),
    "output_name_not_lower_case": ('"test.f"', "x: Float = 1.0", "-> Outputs(Image=Image)", None, "output 'Image'"),
    "missing_annotation": ('"test.f"', "x=1.0", "-> Image", "x", "annotation"),
    "not_a_port_kind": ('"test.f"', "x: float = 1.0", "-> Image", "x", "not a port kind"),
    "unevaluable_string_annotation": ('"test.f"', "x: 'Flaot()' = 1.0", "-> Image", "x", "NameError"),
    "var_positional": ('"test.f"', "*x: Float", "-> Image", "x", "*args"),
    "var_keyword": ('"test.f"', "**x: Float", "-> Image", "x", "**kwargs"),
    "positional_only": ('"test.f"', "x: Float = 1.0, /", "-> Image", "x", "positional-only"),
    "missing_return_annotation": ('"test.f"', "x: Float = 1.0", "", None, "return annotation"),
    "return_not_an_output_kind": ('"test.f"', "x: Float = 1.0", "-> Color", None, "cannot be an output"),
    "outputs_entry_not_an_output_kind": ('"test.f"', "x: Float = 1.0", "-> Outputs(a=Image, b=String)", None, "output 'b'"),
    "empty_outputs": ('"test.f"', "x: Float = 1.0", "-> Outputs()", None, "at least one output"),
    "outputs_as_an_input": ('"test.f"', "x: Outputs(a=Image)", "-> Image", "x", "return annotation"),
    "image_default": ('"test.f"', "x: Image = None", "-> Image", "x", "cannot have a default"),
    "mask_default": ('"test.f"', "x: Mask = None", "-> Image", "x", "cannot have a default"),
    "path_default": ('"test.f"', "x: Path = '/tmp'", "-> Image", "x", "cannot have a default"),
    "float_default_str": ('"test.f"', "x: Float = 'four'", "-> Image", "x", "'four'"),
    "float_default_nan": ('"test.f"', "x: Float = float('nan')", "-> Image", "x", "finite"),
    "int_default_bool": ('"test.f"', "x: Int = True", "-> Image", "x", "integer"),
    "int_default_float": ('"test.f"', "x: Int = 1.5", "-> Image", "x", "integer"),
    "bool_default_int": ('"test.f"', "x: Bool = 1", "-> Image", "x", "True or False"),
    "string_default_int": ('"test.f"', "x: String = 3", "-> Image", "x", "str"),
    "enum_default_not_an_option": ('"test.f"', "x: Enum('a', 'b') = 'c'", "-> Image", "x", "not one of the options"),
    "enum_without_options": ('"test.f"', "x: Enum = 'a'", "-> Image", "x", "needs its options"),
    "color_default_three_numbers": ('"test.f"', "x: Color = (1, 0, 0)", "-> Image", "x", "4 finite numbers"),
    "vec2_default_three_numbers": ('"test.f"', "x: Vec2 = (1, 0, 0)", "-> Image", "x", "2 finite numbers"),
    "vec3_default_str": ('"test.f"', "x: Vec3 = 'up'", "-> Image", "x", "3 finite numbers"),
    "float_default_out_of_range": ('"test.f"', "x: Float(range=(0, 1)) = 2.0", "-> Image", "x", "outside the range"),
    "int_default_out_of_range": ('"test.f"', "x: Int(range=(1, 4)) = 0", "-> Image", "x", "outside the range"),
    "range_malformed": ('"test.f"', "x: Float(range=(0,)) = 0.0", "-> Image", "x", "range must be"),
    "range_reversed": ('"test.f"', "x: Float(range=(1, 0)) = 0.5", "-> Image", "x", "low end above"),
    "image_channels": ('"test.f"', "x: Image(channels='rgb')", "-> Image", "x", "channels"),
}


def check_declaration_error(tmp_path, case):
    """Declares `case` in a file and checks the error names the file, the def's line, the function,
    the parameter (when the case has one) and the cause."""
    arguments, parameters, returns, parameter, words = case
    body = "..." if arguments.endswith("doc=None") else '"""Has a docstring."""'
    path = tmp_path / "broken.py"
    path.write_text(f"from pyrograph_plugin import *\n\n@node({arguments})\ndef broken({parameters}) {returns}:\n    {body}\n")
    with pytest.raises(PluginDeclarationError) as error:
        load(path)
    message = str(error.value)
    assert f"{path}:{def_line(path, 'def broken(')}: function 'broken'" in message
    if parameter is not None:
        assert f"parameter '{parameter}'" in message
    assert words in message


@pytest.mark.parametrize("case", ERRORS.values(), ids=ERRORS.keys())
def test_declaration_errors_name_the_function_the_parameter_and_the_def(tmp_path, case):
    check_declaration_error(tmp_path, case)


def test_node_without_a_type_name_is_refused(tmp_path):
    path = write(tmp_path, """
        from pyrograph_plugin import node, Image

        @node
        def bare() -> Image:
            \"\"\"Bare.\"\"\"
    """)
    with pytest.raises(PluginDeclarationError, match=rf"{path}:{def_line(path, 'def bare(')}: .*needs a type name"):
        load(path)


def test_the_doc_is_the_first_paragraph_of_the_docstring_on_one_line(tmp_path):
    path = write(tmp_path, '''
        from pyrograph_plugin import node, Image

        @node("test.doc")
        def documented() -> Image:
            """Makes
               a  frame.

            Details that stay out of the summary.
            """
    ''')
    assert load(path).documented.__pyrograph__.doc == "Makes a frame."
