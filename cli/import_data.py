"""``acid import``: bring a CSV or MATLAB .mat export into the acid HDF5 layout."""

from __future__ import annotations

from pathlib import Path

import typer

from acid._io import file_sha256
from acid.data import ChannelMap, from_csv, from_mat
from acid.errors import DataError
from acid_cli._common import handle_errors, print_table, write_summary

CSV_SUFFIXES = (".csv", ".txt")
MAT_SUFFIXES = (".mat",)


@handle_errors
def import_data(
    src: Path = typer.Argument(..., help="CSV (header row) or MATLAB .mat file to import."),
    map_path: Path = typer.Option(..., "--map", "-m",
                                  help="Channel map (TOML or JSON): time column, Ts, and "
                                       "{channel: column, unit}; see datasets/FORMAT.md."),
    out: Path = typer.Option(..., "--out", "-o", help="HDF5 dataset to write (atomically)."),
    min_samples: int = typer.Option(2, "--min-samples",
                                    help="Refuse records shorter than this many samples."),
    json_out: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
) -> None:
    """Import SRC through an explicit channel map, validate it and write an acid dataset."""
    cmap = ChannelMap.from_file(map_path)
    suffix = src.suffix.lower()
    if suffix in CSV_SUFFIXES:
        ds = from_csv(src, cmap)
    elif suffix in MAT_SUFFIXES:
        ds = from_mat(src, cmap)
    else:
        raise DataError(f"{src}: unknown file type {suffix or '(none)'!r} "
                        f"(expected {', '.join(CSV_SUFFIXES + MAT_SUFFIXES)})")
    ds.validate(min_samples=min_samples)
    ds.metadata.update({"source_sha256": file_sha256(src), "channel_map_file": str(map_path),
                        "channel_map_sha256": file_sha256(map_path)})
    ds.to_hdf5(out)
    rows = [[n, ds.units[n], f"{v.min():.3g}", f"{v.mean():.3g}", f"{v.max():.3g}"]
            for n, v in ds.channels.items()]
    print_table(f"{out}: {len(ds)} samples, {ds.duration:g} s at Ts = {ds.Ts:g} s, from {src}",
                ["channel", "unit", "min", "mean", "max"], rows)
    write_summary(json_out, {"command": "import", "src": str(src), "out": str(out),
                             "samples": len(ds), "Ts_s": ds.Ts, "channels": list(ds.channels)})
