"""Returned values the output checks cannot read (a float too big for a double) are that output's
error, and the worker lives on to cook again."""

import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "host"))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from test_host import Host, cook  # noqa: E402  (the worker's test driver)

NODES = '''
from pyrograph_plugin import node, Float


@node("test.huge", doc="Returns an int too big for a float.")
def huge(x: Float = 1.0) -> Float:
    return 10 ** 400


@node("test.fine", doc="Returns its input.")
def fine(x: Float = 1.0) -> Float:
    return x
'''


def test_an_unreadable_return_is_a_port_error_and_the_worker_goes_on(tmp_path):
    path = tmp_path / "nodes.py"
    path.write_text(NODES)
    host = Host(tmp_path)
    host.hello()
    try:
        reply = cook(host, path, "test.huge", params={"x": 1.0})
        assert (reply["op"], reply["kind"]) == ("error", "port"), reply
        assert "the returned value could not be read" in reply["message"], reply
        again = cook(host, path, "test.fine", params={"x": 2.5})
        assert again["op"] == "result" and again["outputs"][0]["value"] == 2.5, again
    finally:
        host.close()
