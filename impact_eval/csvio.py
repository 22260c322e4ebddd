"""``episodes.csv``: crash-safe appends (flush + fsync per row), resume, sorted atomic rewrite.

Only the sweep's parent process writes the file. Cells are written with ``repr`` for floats, so
values round-trip exactly and the final, sorted file depends only on the rows, not on the order
in which workers finished them.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path

from impact_control.errors import InvalidArgumentError
from impact_eval.grid import format_value
from impact_eval.metrics import ADDED_COLUMNS, EPISODE_COLUMNS

EpisodeKey = tuple[str, str, int]
"""``(method, canonical param value text, episode index)``: identifies a row."""


def format_cell(value: object) -> str:
    """Text of one CSV cell: ``repr`` for floats (exact round trip), ``str`` otherwise."""
    if isinstance(value, float):
        return "nan" if math.isnan(value) else repr(value)
    return str(value)


def row_key(row: Mapping[str, str]) -> EpisodeKey:
    """Resume/sort key of a row read back from the CSV."""
    return row["method"], format_value(float(row["param_value"])), int(row["episode"])


def _sort_key(row: Mapping[str, str]) -> tuple[str, float, int]:
    """Deterministic order: method name, then numeric parameter value, then episode."""
    return row["method"], float(row["param_value"]), int(row["episode"])


def _encode(rows: Iterable[Mapping[str, object]], header: bool) -> str:
    """CSV text of ``rows`` (and the header line if ``header``)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    if header:
        writer.writerow(EPISODE_COLUMNS)
    for row in rows:
        writer.writerow([format_cell(row[c]) for c in EPISODE_COLUMNS])
    return buf.getvalue()


def encode_rows(rows: Iterable[Mapping[str, object]]) -> str:
    """The text of an ``episodes.csv`` holding ``rows`` in the given order, header included."""
    return _encode(rows, header=True)


def repair_tail(path: Path) -> None:
    """Drop a last line cut short by a crash mid-write (anything after the last newline)."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with path.open("r+b") as f:
            f.truncate(data.rfind(b"\n") + 1)


def read_rows(path: Path, older: bool = False) -> list[dict[str, str]]:
    """Rows of an existing ``episodes.csv`` as strings (the file's header must match).

    Text after the last newline (a row torn by a crash) is ignored, as are malformed rows.
    ``older``: a file written by an older impact-eval (``older_columns_missing``) is read
    as it is, its rows without the columns it lacks (``reproduce`` compares committed tables
    on their own columns); otherwise such a file is refused (it cannot be resumed).
    """
    text = path.read_text()
    with io.StringIO(text[: text.rfind("\n") + 1], newline="") as f:
        reader = csv.DictReader(f)
        columns = tuple(reader.fieldnames or ())
        missing = older_columns_missing(columns)
        if missing is not None and not older:
            raise InvalidArgumentError(
                f"{path} was written by an older impact-eval (no {', '.join(missing)} columns) "
                "and cannot be resumed; run into a new --out directory")
        if missing is None and columns != EPISODE_COLUMNS:
            raise InvalidArgumentError(
                f"{path} is not an impact-eval episodes.csv (columns {reader.fieldnames})"
            )
        try:
            return [dict(r) for r in reader if _well_formed(r)]
        except csv.Error as exc:
            raise InvalidArgumentError(f"{path} is corrupt: {exc}") from None


def file_columns(path: Path) -> tuple[str, ...]:
    """The header of an ``episodes.csv`` (its first line's column names)."""
    with path.open(newline="") as f:
        return tuple(next(csv.reader(f), []))


def older_columns_missing(columns: tuple[str, ...]) -> tuple[str, ...] | None:
    """The columns an older impact-eval did not write yet, when ``columns`` is the header of
    such a file (``EPISODE_COLUMNS`` less the columns of one or more ``ADDED_COLUMNS``
    dates, in order); None for any other header."""
    added = [c for group in ADDED_COLUMNS.values() for c in group]
    missing = tuple(c for c in EPISODE_COLUMNS if c not in columns)
    if not missing or not set(missing) <= set(added):
        return None
    if columns != tuple(c for c in EPISODE_COLUMNS if c not in missing):
        return None
    if not all(set(g) <= set(missing) or not set(g) & set(missing)
               for g in ADDED_COLUMNS.values()):
        return None
    return missing


def _well_formed(row: Mapping[str | None, str | None]) -> bool:
    """True for a complete row with a parseable key (a torn line is skipped)."""
    if None in row or None in row.values():
        return False
    try:
        row_key(row)  # type: ignore[arg-type]
    except (KeyError, ValueError):
        return False
    return True


class EpisodeLog:
    """Append-only episode log with durable per-row writes."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._file: io.TextIOWrapper | None = None

    def open(self) -> None:
        """Open for appending (creating the file with its header if needed)."""
        fresh = not self.path.exists() or self.path.stat().st_size == 0
        if not fresh:
            repair_tail(self.path)
        self._file = self.path.open("a", newline="")
        if fresh:
            self._write(_encode([], header=True))

    def append(self, row: Mapping[str, object]) -> None:
        """Write one row and make it durable (flush + fsync) before returning."""
        self._write(_encode([row], header=False))

    def _write(self, text: str) -> None:
        assert self._file is not None, "EpisodeLog.open() first"
        self._file.write(text)
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._file is not None:
            self._file.close()
            self._file = None

    def finalize(self) -> int:
        """Rewrite the file de-duplicated and sorted, atomically (temp file + rename).

        Returns:
            Number of rows in the final file.
        """
        self.close()
        unique: dict[EpisodeKey, dict[str, str]] = {}
        for row in read_rows(self.path):
            unique.setdefault(row_key(row), row)
        rows = sorted(unique.values(), key=_sort_key)
        tmp = self.path.with_name(self.path.name + ".tmp")
        with tmp.open("w", newline="") as f:
            f.write(_encode(rows, header=True))
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.path)
        _fsync_dir(self.path.parent)
        return len(rows)


def _fsync_dir(path: Path) -> None:
    """Make a rename in ``path`` durable (best effort; not all filesystems allow it)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
