"""Small CSV reader/writer shared by calibration sets and RSSI traces.

Files are plain comma-separated text with a header row; lines starting with ``#`` are
comments (kept, so provenance survives) and blank lines are skipped. Every row keeps its
physical line number so errors can say exactly where a file is wrong. Writes are atomic
(temporary file + rename) so nothing is half-written.
"""

from __future__ import annotations

import csv
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from mrcomm.errors import InputError, did_you_mean
from mrcomm.fileio import atomic_write


@dataclass(frozen=True)
class CsvTable:
    """The rows of a CSV file, keyed by column name, with their line numbers."""

    path: Path
    columns: tuple[str, ...]
    rows: tuple[tuple[int, dict[str, str]], ...]
    comments: tuple[str, ...]

    def error(self, lineno: int, column: str, message: str) -> InputError:
        return InputError(message, file=self.path, field=f"line {lineno}, column {column}")

    def number(self, lineno: int, row: dict[str, str], column: str) -> float:
        """A finite float from a cell, or an :class:`InputError` naming line and column."""
        text = row[column]
        try:
            value = float(text)
        except ValueError:
            raise self.error(lineno, column, f"{text!r} is not a number") from None
        if value != value or value in (float("inf"), float("-inf")):
            raise self.error(lineno, column, f"{text!r} is not a finite number")
        return value


def read_csv(path: str | Path, required: Sequence[str]) -> CsvTable:
    """Read a commented CSV and check the ``required`` columns are present.

    Column names are matched case-insensitively; extra columns are allowed (and
    ignored by callers) because measurement logs often carry timestamps or notes.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError("file not found", file=p) from None
    except IsADirectoryError:
        raise InputError("is a directory, expected a CSV file", file=p) from None
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"cannot read: {err}", file=p) from None
    comments: list[str] = []
    numbered: list[tuple[int, str]] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if stripped.startswith("#"):
            comments.append(stripped[1:].strip())
        elif stripped:
            numbered.append((lineno, line))
    if not numbered:
        raise InputError(f"no header row (expected columns {', '.join(required)})", file=p)
    parsed = list(csv.reader(line for _, line in numbered))
    header_line = numbered[0][0]
    columns = tuple(name.strip().lower() for name in parsed[0])
    for name in required:
        if name not in columns:
            hint = did_you_mean(name, columns)
            raise InputError(
                f"missing column {name!r}{hint} (header has: {', '.join(columns)})",
                file=p,
                field=f"line {header_line}",
            )
    rows: list[tuple[int, dict[str, str]]] = []
    for (lineno, _), cells in zip(numbered[1:], parsed[1:], strict=True):
        if len(cells) < len(columns):
            raise InputError(
                f"{len(cells)} values, expected {len(columns)} ({', '.join(columns)})",
                file=p,
                field=f"line {lineno}",
            )
        rows.append((lineno, {c: v.strip() for c, v in zip(columns, cells, strict=False)}))
    return CsvTable(p, columns, tuple(rows), tuple(comments))


def write_csv(
    path: str | Path,
    columns: Sequence[str],
    rows: Iterable[Sequence[object]],
    comments: Sequence[str] = (),
) -> None:
    """Write ``# comment`` lines, a header and rows, atomically."""

    def write(tmp: Path) -> None:
        with tmp.open("w", encoding="utf-8", newline="") as fh:
            for comment in comments:
                fh.write(f"# {comment}\n" if comment else "#\n")
            writer = csv.writer(fh, lineterminator="\n")
            writer.writerow(columns)
            writer.writerows(rows)

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, write)
