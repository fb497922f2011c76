"""pyrograph: load, edit and cook procedural-fire node graphs, with frames as numpy arrays.

    import pyrograph
    g = pyrograph.Graph.load("graphs/flame-cards.ron")
    g.set("calm.turbulence", 0.8)
    frames = g.cook("calm.clip", frames=range(12))   # 12 H×W×4 float32 arrays

The same documents, node registry and evaluator as the `pyrograph` CLI and the editor. Cooks
release the GIL and stop on Ctrl-C (KeyboardInterrupt); errors raise `GraphError` with `.node`,
`.port` and `.message`.
"""

from ._native import (
    Clip,
    Contours,
    FrameMemory,
    Graph,
    GraphError,
    Problem,
    Value,
    __version__,
    describe,
    limits,
    nodes,
    set_limits,
)

__all__ = ["Clip", "Contours", "FrameMemory", "Graph", "GraphError", "Problem", "Value", "__version__", "describe", "limits", "nodes", "set_limits"]
