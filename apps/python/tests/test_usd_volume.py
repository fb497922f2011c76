"""The USD stage beside a VDB sequence, read with Pixar's own USD (PyPI `usd-core`):
`volume.write_vdb` with `usd` on writes a Volume prim whose fields are OpenVDBAsset prims, each
with a `filePath` sampled at every frame, pointing at VDB files that exist; usdchecker's validators
report no errors."""

import os

import pytest

import pyrograph

if os.environ.get("CI") == "true":
    from pxr import Sdf, Usd, UsdValidation, UsdVol  # CI installs usd-core: a missing package fails instead of skipping
else:
    pytest.importorskip("pxr", reason="pip install usd-core (.ci/run installs it)")
    from pxr import Sdf, Usd, UsdValidation, UsdVol

FRAMES = 6

GRAPH = """(
    version: 3,
    nodes: {
        "source": (type: "volume.source", params: {"center": (0.0, 0.2, 0.0), "radius": 0.2}),
        "sim": (type: "volume.simulate", params: {"frames": 6, "voxel_size": 0.1}),
        "cache": (type: "volume.write_vdb", params: {"pattern": "cache/smoke_####.vdb", "fields": "density temperature vel", "usd": true, "usd_path": "smoke.usda"}),
    },
    edges: [("source.source", "sim.source"), ("sim.volume", "cache.volume")],
)
"""


def test_the_volume_prim_samples_a_file_per_frame_that_exists(tmp_path):
    pyrograph.Graph.from_ron(GRAPH).render(out=tmp_path)
    stage = Usd.Stage.Open(str(tmp_path / "smoke.usda"))
    volume = UsdVol.Volume(stage.GetPrimAtPath("/World/volume"))
    assert volume, "a Volume prim"
    fields = volume.GetFieldPaths()
    assert sorted(fields) == ["density", "temperature", "vel"]
    for name, path in fields.items():
        asset = UsdVol.OpenVDBAsset(stage.GetPrimAtPath(path))
        assert asset, f"{path} is an OpenVDBAsset"
        assert asset.GetFieldNameAttr().Get() == name
        file_path = asset.GetFilePathAttr()
        assert file_path.GetTimeSamples() == [float(t) for t in range(FRAMES)]
        for t in range(FRAMES):
            value = file_path.Get(t)
            assert isinstance(value, Sdf.AssetPath)
            resolved = (tmp_path / value.path).resolve()
            assert resolved.is_file(), f"{value.path} at frame {t}"
            assert resolved.name == f"smoke_{t:04d}.vdb"
    types = {name: UsdVol.OpenVDBAsset(stage.GetPrimAtPath(path)).GetFieldDataTypeAttr().Get() for name, path in fields.items()}
    assert types == {"density": "float", "temperature": "float", "vel": "float3"}
    registry = UsdValidation.ValidationRegistry()
    context = UsdValidation.ValidationContext(registry.GetOrLoadAllValidators())
    errors = [e.GetMessage() for e in context.Validate(stage) if e.GetType() == UsdValidation.ValidationErrorType.Error]
    assert errors == []
