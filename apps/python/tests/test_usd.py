"""USD stages read on the other side: `particles.write_usd` stages opened with Pixar's own USD
(PyPI `usd-core`): the Points prim has one time sample per frame, its points equal pyrograph's
particles (cooked through the Python API) at three frames, the primvars are there with the
interpolation declared, and usdchecker's validators report no errors; `.usda` and `.usd` alike.

usd-core 26 ships no `usdchecker` script; the script is a front end to `pxr.UsdValidation`, whose
registered validators (UsdCoreValidators, UsdGeomValidators — stage metadata, encapsulation —
and the rest) this test runs on each stage as the script does."""

import os

import numpy as np
import pytest

import pyrograph

if os.environ.get("CI") == "true":
    from pxr import Usd, UsdGeom, UsdValidation  # CI installs usd-core: a missing package fails instead of skipping
else:
    pxr = pytest.importorskip("pxr", reason="pip install usd-core (.ci/run installs it)")
    from pxr import Usd, UsdGeom, UsdValidation

FRAMES = 12

GRAPH = """(
    version: 3,
    nodes: {
        "roots": (type: "particles.roots", params: {"layout": "row", "count": 3, "spacing": 1.5}),
        "wind": (type: "particles.wind_field", params: {"wind": (0.3, 0.0, 0.0), "seed": 4}),
        "flame": (type: "particles.particle_flame", params: {"frames": 12, "steps": 10, "flicker": 0.3, "seed": 2}),
        "cube": (type: "particles.mesh_load", params: {"source": "cube", "size": 2.0}),
        "spread": (type: "particles.fire_spread", params: {"frames": 12}),
        "text": (type: "particles.write_usd", params: {"path": "fire.usda"}),
        "plain": (type: "particles.write_usd", params: {"path": "fire.usd", "name": "embers_and_flames"}),
    },
    edges: [
        ("roots.roots", "flame.roots"),
        ("wind.wind", "flame.wind"),
        ("flame.flames", "text.particles"),
        ("cube.mesh", "spread.mesh"),
        ("cube.mesh", "text.mesh"),
        ("spread.spread", "text.spread"),
        ("flame.flames", "plain.particles"),
    ],
)
"""


def validation_errors(path):
    """What usdchecker reports for a stage: every registered validator's errors, as text."""
    registry = UsdValidation.ValidationRegistry()
    context = UsdValidation.ValidationContext(registry.GetOrLoadAllValidators())
    found = context.Validate(Usd.Stage.Open(str(path)))
    return [f"{e.GetType()}: {e.GetMessage()}" for e in found if e.GetType() == UsdValidation.ValidationErrorType.Error]


@pytest.fixture(scope="module")
def stages(tmp_path_factory):
    out = tmp_path_factory.mktemp("usd")
    graph = pyrograph.Graph.from_ron(GRAPH)
    graph.render(out=out)
    flames = graph.cook("flame.flames")
    return out, flames


@pytest.mark.parametrize("name, prim", [("fire.usda", "/World/flames"), ("fire.usd", "/World/embers_and_flames")])
def test_points_have_a_sample_per_frame_and_equal_the_particles(stages, name, prim):
    out, flames = stages
    stage = Usd.Stage.Open(str(out / name))
    assert stage.GetDefaultPrim().GetPath() == "/World"
    assert UsdGeom.GetStageUpAxis(stage) == "Y"
    assert stage.GetStartTimeCode() == 0 and stage.GetEndTimeCode() == FRAMES - 1
    points = UsdGeom.Points(stage.GetPrimAtPath(prim))
    assert points, f"{prim} is a Points prim"
    assert points.GetPointsAttr().GetTimeSamples() == [float(t) for t in range(FRAMES)]
    for frame in (0, 5, FRAMES - 1):
        expected = flames[frame]
        got = np.asarray(points.GetPointsAttr().Get(frame), dtype=np.float32)
        assert got.shape == expected["position"].shape and len(got) > 0
        np.testing.assert_array_equal(got, expected["position"])
        widths = np.asarray(points.GetWidthsAttr().Get(frame))
        np.testing.assert_allclose(widths, 2 * np.abs(expected["size"]).max(axis=1), rtol=1e-6)
        api = UsdGeom.PrimvarsAPI(points)
        for primvar, values in (("displayColor", expected["center"][:, :3]), ("age", expected["weight"]), ("flame", expected["group"])):
            pv = api.GetPrimvar(primvar)
            assert pv and pv.GetInterpolation() == UsdGeom.Tokens.vertex, primvar
            np.testing.assert_allclose(np.asarray(pv.Get(frame), dtype=np.float64), values, rtol=1e-6)
        assert points.GetExtentAttr().Get(frame) is not None


def test_the_mesh_and_the_spreading_front_are_beside_the_flames(stages):
    out, _ = stages
    stage = Usd.Stage.Open(str(out / "fire.usda"))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/mesh"))
    assert mesh and set(mesh.GetFaceVertexCountsAttr().Get()) == {3}
    assert mesh.GetSubdivisionSchemeAttr().Get() == "none"
    assert len(mesh.GetFaceVertexIndicesAttr().Get()) == 3 * len(mesh.GetFaceVertexCountsAttr().Get())
    front = UsdGeom.BasisCurves(stage.GetPrimAtPath("/World/front"))
    assert front and front.GetTypeAttr().Get() == "linear"
    assert front.GetPointsAttr().GetTimeSamples() == [float(t) for t in range(FRAMES)]
    # The front grows from the ignition point: more of it at the end than at the start.
    assert len(front.GetPointsAttr().Get(FRAMES - 1)) > len(front.GetPointsAttr().Get(0))
    counts = front.GetCurveVertexCountsAttr().Get(FRAMES - 1)
    assert sum(counts) == len(front.GetPointsAttr().Get(FRAMES - 1)) and min(counts) >= 2
    roots = UsdGeom.Points(stage.GetPrimAtPath("/World/roots"))
    assert roots and UsdGeom.PrimvarsAPI(roots).GetPrimvar("age").GetInterpolation() == UsdGeom.Tokens.vertex


@pytest.mark.parametrize("name", ["fire.usda", "fire.usd"])
def test_usdchecker_reports_no_errors(stages, name):
    out, _ = stages
    assert validation_errors(out / name) == []


def test_usdchecker_would_catch_a_stage_without_its_metadata(tmp_path):
    """The check can fail: the same points without upAxis and metersPerUnit are errors."""
    bare = tmp_path / "bare.usda"
    bare.write_text('#usda 1.0\n(\n    defaultPrim = "World"\n)\ndef Xform "World"\n{\n    def Points "p"\n    {\n        point3f[] points = [(0, 0, 0)]\n    }\n}\n')
    assert validation_errors(bare), "a stage without upAxis/metersPerUnit passes the validators"


def test_a_binary_stage_is_refused_with_the_way_round(tmp_path):
    graph = pyrograph.Graph.from_ron(GRAPH)
    graph.set("plain.path", "fire.usdc")
    with pytest.raises(pyrograph.GraphError) as e:
        graph.render(out=tmp_path, nodes=["plain"])
    assert "usdcat" in str(e.value) and "plain" in str(e.value)
    assert not (tmp_path / "fire.usdc").exists()


CLOTH = """(
    version: 3,
    nodes: {
        "silk": (type: "cloth.mass_spring_flame", params: {"frames": 6, "count": 3}),
        "stage": (type: "cloth.write_usd", params: {"path": "cloth.usda"}),
    },
    edges: [("silk.cloth", "stage.cloth")],
)
"""


def test_cloth_flames_are_one_animated_mesh_of_quads(tmp_path):
    graph = pyrograph.Graph.from_ron(CLOTH)
    graph.render(out=tmp_path)
    stage = Usd.Stage.Open(str(tmp_path / "cloth.usda"))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/cloth"))
    assert mesh and mesh.GetSubdivisionSchemeAttr().Get() == "none"
    assert mesh.GetPointsAttr().GetTimeSamples() == [float(t) for t in range(6)]
    counts = mesh.GetFaceVertexCountsAttr().Get()
    assert set(counts) == {4} and len(mesh.GetFaceVertexIndicesAttr().Get()) == 4 * len(counts)
    first, last = (np.asarray(mesh.GetPointsAttr().Get(t)) for t in (0, 5))
    assert first.shape == last.shape and len(first) > 3 * 4, "three cloths of masses"
    assert not np.allclose(first, last), "the cloths move"
    api = UsdGeom.PrimvarsAPI(mesh)
    st = np.asarray(api.GetPrimvar("st").Get())
    assert api.GetPrimvar("st").GetInterpolation() == UsdGeom.Tokens.vertex and len(st) == len(first)
    assert st.min() == 0.0 and st.max() == 1.0
    assert sorted(set(api.GetPrimvar("flame").Get())) == [0, 1, 2]
    assert validation_errors(tmp_path / "cloth.usda") == []
