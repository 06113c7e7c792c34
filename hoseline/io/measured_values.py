"""Read measured values (one quantity, e.g. hose lengths' deviations from nominal) from a CSV file.

The file holds one number per row, or several columns with a header row naming them (then `column`
chooses one); blank lines and lines starting with # are skipped.  A cell that is not a number is
refused with its line.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path


def read_measured_values(path: Path, column: str | None = None) -> tuple[float, ...]:
    """The numbers of one column of the CSV file `path` (its only column, or the one headed `column`).

    Raises ValueError naming the file, the line and the fix; OSError when it cannot be read.
    """
    with open(path, newline="", encoding="utf-8") as handle:
        rows = [(line, [cell.strip() for cell in row]) for line, row in enumerate(csv.reader(handle), start=1)
                if row and any(cell.strip() for cell in row) and not row[0].lstrip().startswith("#")]
    if not rows:
        raise ValueError(f"{path}: no values in the file: give one number per row")
    header = None if _is_number(rows[0][1][0]) else rows[0][1]
    if header is not None:
        rows = rows[1:]
    width = len(header) if header is not None else len(rows[0][1])
    if column is not None:
        if header is None or column not in header:
            raise ValueError(f"{path}: column = \"{column}\": the file's header row has "
                             f"{', '.join(header) if header else 'no names (its first row is numbers)'}")
        index = header.index(column)
    elif width == 1:
        index = 0
    else:
        raise ValueError(f"{path}: {width} columns: name the one to use with column = \"...\" (its header)")
    values = []
    for line, row in rows:
        cell = row[index] if index < len(row) else ""
        if not _is_number(cell) or not math.isfinite(float(cell)):
            raise ValueError(f"{path} line {line}: {cell!r} is not a finite number: fix or remove the row")
        values.append(float(cell))
    return tuple(values)


def _is_number(text: str) -> bool:
    """Whether `text` reads as a float."""
    try:
        float(text)
    except ValueError:
        return False
    return True
