"""ColorRamp and Curve ports: declared with keys as defaults (checked), handed to the function as
read-only (K, 1 + width) float64 arrays by the worker."""

import pathlib
import sys

import pytest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "host"))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from pyrograph_plugin import ColorRamp, Curve, Float, Image, PluginDeclarationError, node  # noqa: E402
from test_host import Host, cook  # noqa: E402  (the worker's test driver)

RAMPS = '''
import numpy as np
from pyrograph_plugin import node, ColorRamp, Curve, Float


@node("test.ramps", doc="Sums what it got.")
def ramps(ramp: ColorRamp = [(0.0, 0, 0, 0, 1), (1.0, 1, 0.8, 0.3, 1)], falloff: Curve = [(0.0, 0.0), (1.0, 1.0)]) -> Float:
    assert ramp.dtype == np.float64 and not ramp.flags.writeable
    return float(ramp.sum() + 10 * falloff.shape[0] + 100 * ramp.shape[1])
'''


def test_ramp_and_curve_defaults_are_declared_as_rows():
    @node("test.grade")
    def grade(image: Image, ramp: ColorRamp = [(0.0, 0, 0, 0, 1), (1.0, 1, 0.5, 0.25, 1)], curve: Curve = [(0, 0), (1, 2)]) -> Image:
        """Grades."""
        return image

    ports = {p["name"]: p for p in grade.__pyrograph__.as_dict()["inputs"]}
    assert ports["ramp"]["kind"] == "color_ramp"
    assert ports["ramp"]["default"] == [[0.0, 0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 0.5, 0.25, 1.0]]
    assert (ports["curve"]["kind"], ports["curve"]["default"]) == ("curve", [[0.0, 0.0], [1.0, 2.0]])


@pytest.mark.parametrize("kind, default, words", [
    (Curve, [(1.0, 0.0), (0.0, 1.0)], "go in position order"),
    (Curve, [(0.0, 1.0, 2.0)], "keys of 2 finite numbers"),
    (ColorRamp, [(0.0, 1.0)], "keys of 5 finite numbers"),
    (ColorRamp, [], "keys of 5 finite numbers"),
    (Curve, [(0.0, float("nan"))], "keys of 2 finite numbers"),
])
def test_bad_keys_are_declaration_errors(kind, default, words):
    with pytest.raises(PluginDeclarationError, match=words):
        @node("test.bad")
        def bad(x: kind = default) -> Float:
            """Bad."""
            return 0.0


def test_the_worker_hands_keys_over_as_read_only_arrays(tmp_path):
    path = tmp_path / "ramps.py"
    path.write_text(RAMPS)
    host = Host(tmp_path)
    host.hello()
    try:
        params = {"ramp": [[0.0, 0, 0, 0, 1], [1.0, 1, 0.8, 0.3, 1]], "falloff": [[0.0, 0.0], [0.5, 0.2], [1.0, 1.0]]}
        reply = cook(host, path, "test.ramps", params=params)
        assert reply["op"] == "result", reply
        assert reply["outputs"][0]["value"] == pytest.approx(5.1 + 30 + 500)
        bad = cook(host, path, "test.ramps", params={"ramp": [[0.0, 1.0]], "falloff": [[0.0, 0.0]]})
        assert bad["op"] == "fatal", "keys of the wrong width are a malformed request"
    finally:
        host.close()
