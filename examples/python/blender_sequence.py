"""Blender: cook a pyrograph flame into an image sequence and map it onto a plane.

Run inside Blender (Scripting workspace, or `blender --python examples/python/blender_sequence.py`)
with pyrograph installed into Blender's Python:

    <blender>/<version>/python/bin/python3 -m pip install ./apps/python

Not run in CI (it needs Blender). Blender reads image sequences from files, so the frames are
rendered with the graph's own writer (atomic PNGs, as the CLI writes them), then loaded as an
image-sequence texture on an emissive, alpha-blended plane.
"""

import pathlib
import tempfile

import bpy  # noqa: F401  (only inside Blender)

import pyrograph

GRAPH = pathlib.Path(bpy.path.abspath("//")) / "graphs" / "flame-cards.ron"
out = pathlib.Path(tempfile.mkdtemp(prefix="pyrograph-"))

graph = pyrograph.Graph.load(GRAPH)
written = sorted(p for p in graph.render(out=out, nodes=["write_calm"]) if p.name.startswith("calm_"))
print(f"pyrograph wrote {len(written)} frames to {out}")

image = bpy.data.images.load(str(written[0]))
image.source = "SEQUENCE"

bpy.ops.mesh.primitive_plane_add(size=2, location=(0, 0, 1), rotation=(1.5708, 0, 0))
plane = bpy.context.active_object
mat = bpy.data.materials.new("pyrograph flame")
mat.use_nodes = True
mat.blend_method = "BLEND"
nodes, links = mat.node_tree.nodes, mat.node_tree.links
tex = nodes.new("ShaderNodeTexImage")
tex.image = image
tex.image_user.frame_duration = len(written)
tex.image_user.use_auto_refresh = True
emit = nodes.new("ShaderNodeEmission")
mix = nodes.new("ShaderNodeMixShader")
transparent = nodes.new("ShaderNodeBsdfTransparent")
links.new(tex.outputs["Color"], emit.inputs["Color"])
links.new(tex.outputs["Alpha"], mix.inputs["Fac"])
links.new(transparent.outputs[0], mix.inputs[1])
links.new(emit.outputs[0], mix.inputs[2])
links.new(mix.outputs[0], nodes["Material Output"].inputs["Surface"])
plane.data.materials.append(mat)
bpy.context.scene.frame_end = len(written)
