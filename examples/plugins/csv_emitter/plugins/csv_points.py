# An example pyrograph node type written in Python: studio.csv_points reads emitter points from a
# CSV table (from a layout tool, a spreadsheet or a pipeline script) for volume.source's point
# list. pyrograph finds the plugins/ folder beside a graph by itself, so this renders the example
# graph, whose ring of emitters lights one after another:
#
#     pyrograph render examples/plugins/csv_emitter/csv-emitter.ron --out pyrograph-out
import csv

import numpy as np
from pyrograph_plugin import Float, Path, Points, Vec3, node

POSITION = ("x", "y", "z")


@node("studio.csv_points", category="Studio")
def csv_points(
    path: Path(doc="CSV file with columns x,y,z and optionally seconds"),
    scale: Float(range=(1e-6, 1e6), doc="Multiplies every position") = 1.0,
    offset: Vec3(doc="Added to every position after scale") = (0.0, 0.0, 0.0),
) -> Points:
    """Reads emitter points from a CSV file: x, y, z and, when there is one, the seconds each starts.

    The first row that is not a comment names the columns, in any order; x, y and z are needed,
    seconds is optional (without it every point emits from the start), and other columns are
    ignored. Lines starting with # are comments, as is anything after a # on a line. Each
    position becomes position·scale + offset.
    """
    header, rows = _read_table(path)
    columns = {}
    for i, name in enumerate(header):
        if name in columns and name in POSITION + ("seconds",):
            raise ValueError(f"{path}: the header names the column '{name}' twice")
        columns.setdefault(name, i)
    for name in POSITION:
        if name not in columns:
            raise ValueError(
                f"{path}: no column '{name}' in the header {','.join(header)}; "
                "the columns x, y and z are needed (and seconds is optional)"
            )
    wanted = (["seconds"] if "seconds" in columns else []) + list(POSITION)
    if not rows:
        raise ValueError(f"{path}: no points below the header row")
    table = np.array([[_number(path, line, row, name, columns[name]) for name in wanted] for line, row in rows])
    table[:, -3:] = table[:, -3:] * scale + np.asarray(offset, dtype=np.float64)
    if "seconds" in columns and (table[:, 0] < 0).any():
        line = rows[int(np.argmax(table[:, 0] < 0))][0]
        raise ValueError(f"{path}:{line}: seconds must be 0 or more (when the point starts emitting)")
    return table


def _read_table(path):
    """The header's column names (lower-case) and the data rows as (line number, fields)."""
    header = None
    rows = []
    with open(path, newline="", encoding="utf-8-sig") as file:  # -sig: spreadsheets write a BOM
        for line, text in enumerate(file, 1):
            text = text.split("#", 1)[0]
            if not text.strip():
                continue
            fields = [f.strip() for f in next(csv.reader([text], skipinitialspace=True))]
            if header is None:
                header = [f.lower() for f in fields]
            else:
                rows.append((line, fields))
    if header is None:
        raise ValueError(
            f"{path}: the file has no header row; the first line that is not a comment names the columns, e.g. seconds,x,y,z"
        )
    return header, rows


def _number(path, line, row, name, column):
    """The field of column `name` in a data row, as a finite float."""
    if column >= len(row) or not row[column]:
        raise ValueError(f"{path}:{line}: the row has no value in column '{name}'")
    try:
        value = float(row[column])
    except ValueError:
        value = None
    if value is None or not np.isfinite(value):
        raise ValueError(f"{path}:{line}: column '{name}' holds {row[column]!r}, which is not a finite number")
    return value
