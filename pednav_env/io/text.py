"""Reading CSV text safely: every failure is a ``ValueError`` naming the file.

Files are read as UTF-8 (a byte-order mark is skipped). A binary file (a NUL
byte in its first 4 kB), a file in another encoding, or a line the ``csv``
module cannot parse gives one sentence with the file name (and the line),
never a bare decode error.
"""

from __future__ import annotations

import csv
from collections.abc import Iterator
from pathlib import Path

#: Bytes inspected to tell a binary file from text.
SNIFF_BYTES = 4096


def _not_text(path: Path) -> ValueError | None:
    with path.open("rb") as fh:
        head = fh.read(SNIFF_BYTES)
    if b"\x00" in head:
        return ValueError(f"{path.name}: a binary file, not a CSV text file")
    return None


def iter_csv_rows(path: str | Path) -> Iterator[tuple[int, list[str]]]:
    """``(line number, fields)`` of every line of a CSV file (header included)."""
    path = Path(path)
    err = _not_text(path)
    if err is not None:
        raise err
    line = 0
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            for row in reader:
                line = reader.line_num
                yield line, row
    except UnicodeDecodeError as exc:
        byte = exc.object[exc.start : exc.start + 1].hex()
        raise ValueError(
            f"{path.name}: not UTF-8 text (byte 0x{byte} after line {line}); "
            "is it a CSV file? Save it as UTF-8"
        ) from None
    except csv.Error as exc:
        raise ValueError(f"{path.name}: line {line + 1}: not valid CSV ({exc})") from None


def read_header(path: str | Path) -> list[str]:
    """The first line's fields (``ValueError`` for an empty file)."""
    path = Path(path)
    for _, row in iter_csv_rows(path):
        return row
    raise ValueError(f"{path.name}: empty file")


def read_csv_cells(path: str | Path) -> tuple[list[str], list[list[str]], list[int]]:
    """(header, data rows, their line numbers); blank lines skipped."""
    path = Path(path)
    rows = iter_csv_rows(path)
    header = next(rows, None)
    if header is None:
        raise ValueError(f"{path.name}: empty file")
    cells: list[list[str]] = []
    lines: list[int] = []
    for line, row in rows:
        if not row or all(not c.strip() for c in row):
            continue
        cells.append(row)
        lines.append(line)
    return header[1], cells, lines
