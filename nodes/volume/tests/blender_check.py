"""Imports OpenVDB files into Blender (the `bpy` wheel) the way an artist does (File > Import >
OpenVDB, one file or a numbered sequence) and prints, after the marker line, what Blender made of
them as JSON: the object, whether it is a sequence, every grid's name, type, channels and
index-to-object matrix, and the evaluated object's world bounds.

Usage: python blender_check.py FILE [FILE ...]   (several files: one numbered sequence)
"""

import json
import os
import sys

import bpy

MARKER = "== blender_check json"


def main(paths):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    directory = os.path.dirname(paths[0])
    files = [{"name": os.path.basename(p)} for p in paths]
    result = bpy.ops.object.volume_import(filepath=paths[0], directory=directory, files=files)
    obj = bpy.context.view_layer.objects.active
    vol = obj.data
    loaded = vol.grids.load()
    grids = []
    for g in vol.grids:
        grids.append(
            {
                "name": g.name,
                "data_type": g.data_type,
                "channels": g.channels,
                "matrix": [list(r) for r in g.matrix_object],
            }
        )
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    corners = [list(c) for c in evaluated.bound_box]
    out = {
        "operator": sorted(result),
        "object_type": obj.type,
        "loaded": loaded,
        "error": vol.grids.error_message,
        "is_sequence": vol.is_sequence,
        "frame_duration": vol.frame_duration,
        "grids": grids,
        "bounds": [[min(c[a] for c in corners) for a in range(3)], [max(c[a] for c in corners) for a in range(3)]],
        "blender": bpy.app.version_string,
    }
    print(MARKER)
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv[1:])
