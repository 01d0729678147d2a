"""``acid import``: bring a CSV or MATLAB .mat export into the acid HDF5 layout."""

from __future__ import annotations

from pathlib import Path

import typer

from acid._io import file_sha256
from acid.data import ChannelMap, from_csv, from_mat
from acid.errors import DataError
from acid_cli._common import (
    check_paths,
    handle_errors,
    note,
    print_table,
    require_range,
    write_summary,
)

CSV_SUFFIXES = (".csv", ".txt")
MAT_SUFFIXES = (".mat",)


@handle_errors
def import_data(
    src: Path = typer.Argument(..., help="CSV (header row) or MATLAB .mat file to import."),
    map_path: Path = typer.Option(..., "--map", "-m",
                                  help="Channel map (TOML or JSON): time column, Ts, resample "
                                       "and {channel: column, unit}; see datasets/FORMAT.md."),
    out: Path = typer.Option(..., "--out", "-o", help="HDF5 dataset to write (atomically)."),
    min_samples: int = typer.Option(2, "--min-samples",
                                    help="Refuse records shorter than this many samples."),
    json_out: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
) -> None:
    """Import SRC through an explicit channel map, validate it and write an acid dataset."""
    check_paths(inputs={"SRC": src, "--map": map_path},
                outputs={"--out": out, "--json": json_out})
    require_range(min_samples, "--min-samples", 2, None)
    suffix = src.suffix.lower()
    if suffix not in CSV_SUFFIXES + MAT_SUFFIXES:
        raise DataError(f"{src}: unknown file type {suffix or '(none)'!r} "
                        f"(expected {', '.join(CSV_SUFFIXES + MAT_SUFFIXES)})")
    cmap = ChannelMap.from_file(map_path)
    ds = from_csv(src, cmap) if suffix in CSV_SUFFIXES else from_mat(src, cmap)
    ds.validate(min_samples=min_samples)
    ds.metadata.update({"source_sha256": file_sha256(src), "channel_map_file": str(map_path),
                        "channel_map_sha256": file_sha256(map_path)})
    ds.to_hdf5(out)
    resample = ds.metadata.get("resample") or {}
    if resample.get("note"):
        note(f"{src}: {resample['note']}")
    rows = [[n, ds.units[n], f"{v.min():.3g}", f"{v.mean():.3g}", f"{v.max():.3g}"]
            for n, v in ds.channels.items()]
    print_table(f"{out}: {len(ds)} samples, {ds.duration:g} s at Ts = {ds.Ts:g} s, from {src}",
                ["channel", "unit", "min", "mean", "max"], rows)
    write_summary(json_out, {"command": "import", "src": str(src), "out": str(out),
                             "samples": len(ds), "Ts_s": ds.Ts, "channels": list(ds.channels),
                             "resample": resample or None})
