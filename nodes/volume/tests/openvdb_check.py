"""The OpenVDB reference library's view of a .vdb file, for pyrograph's tests (Debian's
python3-openvdb: run with /usr/bin/python3).

    openvdb_check.py dump FILE   prints every grid of FILE as JSON: name, value type, half flag,
                                 voxel size, the world position of index (0,0,0) and (1,1,1),
                                 active voxel count, class and every active voxel's value
    openvdb_check.py make FILE   writes FILE from numpy arrays with the library's default
                                 compression (Blosc + active mask): a float grid "density", a
                                 vec3 grid "vel" and a half float grid "temperature", then dumps it
"""
import json
import sys

import numpy as np
import pyopenvdb as vdb


def dump(path):
    grids, meta = vdb.readAll(path)
    out = {"meta": {k: v for k, v in meta.items() if isinstance(v, (int, float, str))}, "grids": []}
    for g in grids:
        values = []
        for item in g.citerOnValues():
            lo, hi, v = item["min"], item["max"], item["value"]
            v = list(v) if isinstance(v, tuple) else [v]
            for i in range(lo[0], hi[0] + 1):
                for j in range(lo[1], hi[1] + 1):
                    for k in range(lo[2], hi[2] + 1):
                        values.append([i, j, k] + v)
        out["grids"].append({
            "name": g.name,
            "type": g.valueTypeName,
            "half": bool(g.saveFloatAsHalf),
            "class": str(g.gridClass),
            "voxel_size": list(g.transform.voxelSize()),
            "origin": list(g.transform.indexToWorld((0, 0, 0))),
            "world_111": list(g.transform.indexToWorld((1, 1, 1))),
            "active": g.activeVoxelCount(),
            "values": values,
        })
    print(json.dumps(out))


def make(path):
    rng = np.random.default_rng(7)
    transform = vdb.createLinearTransform(voxelSize=0.25)
    transform.translate((1.0, 2.0, 3.0))
    density = vdb.FloatGrid()
    density.name = "density"
    d = np.zeros((13, 9, 11), dtype=np.float32)
    d[2:11, 1:8, 3:10] = rng.random((9, 7, 7), dtype=np.float32)
    density.copyFromArray(d, ijk=(-5, 6, -20), tolerance=0)
    density.transform = transform
    vel = vdb.Vec3SGrid()
    vel.name = "vel"
    v = rng.standard_normal((6, 7, 5, 3)).astype(np.float32)
    vel.copyFromArray(v, ijk=(-3, 7, -18), tolerance=(0.0, 0.0, 0.0))
    vel.transform = transform
    temperature = vdb.FloatGrid()
    temperature.name = "temperature"
    temperature.saveFloatAsHalf = True
    t = (rng.random((20, 4, 4), dtype=np.float32) * 2.0 + 0.25).astype(np.float32)
    temperature.copyFromArray(t, ijk=(-10, 8, -15), tolerance=0)
    temperature.transform = transform
    vdb.write(path, grids=[density, vel, temperature])
    dump(path)


if __name__ == "__main__":
    {"dump": dump, "make": make}[sys.argv[1]](sys.argv[2])
