"""Export a results database to one CSV or Parquet file per table (``mrcomm export``).

DuckDB writes the files itself (no pyarrow needed), from a read-only connection; each
file is written under a temporary name and renamed, so an interrupted export never
leaves a truncated table behind.
"""

from __future__ import annotations

from pathlib import Path

from mrcomm.errors import InputError, did_you_mean
from mrcomm.experiment.store import open_readonly
from mrcomm.experiment.tables import TABLES
from mrcomm.fileio import atomic_write
from mrcomm.output_paths import check_output_dir

FORMATS = {"csv": "(FORMAT csv, HEADER)", "parquet": "(FORMAT parquet)"}


def check_format(fmt: str) -> None:
    if fmt not in FORMATS:
        raise InputError(
            f"unknown format {fmt!r}{did_you_mean(fmt, FORMATS)}; choose csv or parquet",
            field="--format",
        )


def export_tables(db_path: Path, fmt: str, out_dir: Path) -> list[Path]:
    """Write every table of ``db_path`` to ``out_dir/<table>.<fmt>``; return the paths."""
    check_format(fmt)
    con = open_readonly(db_path)  # refuses a missing or incompatible database first
    try:
        check_output_dir(out_dir, "--out")
        out_dir.mkdir(parents=True, exist_ok=True)
        written = []
        for table in TABLES:
            target = out_dir / f"{table}.{fmt}"

            def copy(tmp: Path, table: str = table) -> None:
                quoted = str(tmp).replace("'", "''")
                con.execute(f"COPY (SELECT * FROM {table}) TO '{quoted}' {FORMATS[fmt]}")

            atomic_write(target, copy)
            written.append(target)
        return written
    finally:
        con.close()
