"""``acid import``: bring CSV (also ``.csv.gz``) or MATLAB .mat logs into the acid HDF5 layout,
one experiment per file."""

from __future__ import annotations

import os
import warnings
from collections import defaultdict
from pathlib import Path

import typer

from acid import examples
from acid._io import file_sha256
from acid.data import CHANNEL_NAME, ChannelMap, PlausibilityWarning, import_logs, log_kind
from acid.errors import DataError
from acid_cli._common import (
    check_paths,
    handle_errors,
    note,
    print_table,
    require,
    require_range,
    warn,
    write_summary,
)


@handle_errors
def import_data(
    srcs: list[Path] = typer.Argument(..., metavar="SRC",
                                      help="CSV (header row; .csv.gz read as is) or MATLAB "
                                           ".mat files to import: one experiment per file."),
    map_path: Path = typer.Option(..., "--map", "-m",
                                  help="Channel map (TOML or JSON): time column, Ts, resample, "
                                       "sep/encoding/decimal and {channel: column, unit}; see "
                                       "datasets/FORMAT.md. example:NAME for a bundled one "
                                       "(acid examples)."),
    out: Path = typer.Option(..., "--out", "-o", help="HDF5 dataset to write (atomically)."),
    min_samples: int = typer.Option(2, "--min-samples",
                                    help="Refuse records shorter than this many samples."),
    json_out: Path | None = typer.Option(None, "--json", help="Write a JSON summary here."),
    required_spec: str | None = typer.Option(
        None, "--require",
        help="Channels the dataset must have, checked before it is written: 'model' (what "
             "`acid fit` needs), 'econ' (`acid fit --model econ`) or names separated by "
             "commas; every missing one is named in one error."),
) -> None:
    """Import SRC... through an explicit channel map, check and write one acid dataset.

    Units are converted (km/h, kW, kg/h, degF, ...); values that contradict their declared
    unit get a warning; empty cells up to max_gap_s (a map key) are bridged, and glitches,
    impossible jumps and out-of-range values are flagged: each a warning naming channel
    and time, a quality table per file, and masked in <channel>_censored so fits and
    validations skip them. Clipped and quantised sensors are reported apart from set-points
    held by design; channels the map declares as a constant or an expression are recorded
    as assumed.
    """
    labels = {"SRC" if len(srcs) == 1 else f"SRC {i + 1}": p for i, p in enumerate(srcs)}
    check_paths(inputs={**labels, "--map": map_path},
                outputs={"--out": out, "--json": json_out})
    seen: dict[str, Path] = {}
    for p in srcs:
        key = os.path.realpath(p)
        if key in seen:
            raise DataError(f"SRC {p}: given twice (also as {seen[key]}); each file is one "
                            "experiment")
        seen[key] = p
    require_range(min_samples, "--min-samples", 2, None)
    required = _required(required_spec)
    for p in srcs:
        log_kind(p)
    cmap = ChannelMap.from_file(map_path)
    missing = [n for n in required if n not in cmap.channels]
    if missing:  # before any file is read: one line naming every one
        raise DataError(f"--map {map_path}: has no channel {', '.join(map(repr, missing))} "
                        f"({len(missing)} of the {len(required)} that --require "
                        f"{required_spec} needs; a log that does not measure one can declare "
                        "it in the map as a constant or an expression, recorded as assumed)")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PlausibilityWarning)
        try:
            ds = import_logs(srcs, cmap)
        finally:  # a unit that looks wrong may explain the error that follows
            for w in caught:
                if issubclass(w.category, PlausibilityWarning):
                    warn(w.message)
    ds.validate(require=required, min_samples=min_samples)
    for rec, p in zip(ds.metadata["experiments"], srcs, strict=True):
        rec["source_sha256"] = file_sha256(p)
    if len(srcs) == 1:  # one file: its hash at the top level too, as before several files
        ds.metadata["source_sha256"] = ds.metadata["experiments"][0]["source_sha256"]
    ds.metadata.update({"channel_map_file": str(map_path),
                        "channel_map_sha256": file_sha256(map_path)})
    ds.to_hdf5(out)
    _report(ds, srcs)
    rows = [[n, ds.units[n], f"{v.min():.3g}", f"{v.mean():.3g}", f"{v.max():.3g}",
             "assumed" if n in ds.assumed else ("mask" if n.endswith("_censored")
                                                else "measured")]
            for n, v in ds.channels.items()]
    source = examples.reference_of(srcs[0]) if len(srcs) == 1 else f"{len(srcs)} files"
    print_table(f"{out}: {len(ds)} samples, {ds.duration:g} s at Ts = {ds.Ts:g} s, "
                f"{len(srcs)} experiment{'s' if len(srcs) > 1 else ''}, from {source}",
                ["channel", "unit", "min", "mean", "max", "_what"], rows)
    resample = ds.metadata.get("resample") or {}
    write_summary(json_out, {
        "command": "import", "src": [str(p) for p in srcs], "out": str(out),
        "samples": len(ds), "duration_s": ds.duration, "Ts_s": ds.Ts,
        "channels": list(ds.channels), "assumed": ds.assumed,
        "experiments": [{k: r[k] for k in ("name", "source", "samples", "duration_s",
                                           "checks", "censored", "quality")}
                        for r in ds.metadata["experiments"]],
        "censoring": ds.metadata.get("censoring", []),
        "warnings": [str(w.message) for w in caught
                     if issubclass(w.category, PlausibilityWarning)],
        "resample": resample or None})


def _required(spec: str | None) -> tuple[str, ...]:
    """The channels ``--require`` names: a preset (model, econ) or a comma-separated list."""
    if spec is None:
        return ()
    if spec == "model":
        from acid.data import MODEL_CHANNELS

        return MODEL_CHANNELS
    if spec == "econ":
        from acid.ident.econ import REQUIRED

        return REQUIRED
    names = tuple(n.strip() for n in spec.split(",") if n.strip())
    bad = [n for n in names if not CHANNEL_NAME.fullmatch(n)]
    require(bool(names) and not bad, "--require",
            f"must be 'model', 'econ' or channel names separated by commas, got {spec!r}")
    return names


def _report(ds, srcs: list[Path]) -> None:
    """Notes on what the files hold: resampling, assumed channels, samples flagged as a
    faulty sensor's (a table), sensors that clip or hold a few levels apart from signals
    held by design, masked samples."""
    experiments = ds.metadata["experiments"]
    rows = [[r["name"], q["channel"], q["kind"], q["count"], q["samples"],
             f"{q['first_at_s']:.6g}"] for r in experiments for q in r.get("quality") or []]
    if rows:
        print_table("samples flagged (a faulty sensor, empty cells): masked in "
                    "<channel>_censored, not fitted or scored",
                    ["_file", "_channel", "_flag", "count", "samples", "first at (s)"], rows)
    notes = {r["resample"]["note"] for r in experiments
             if (r.get("resample") or {}).get("note")}
    for text in sorted(notes):
        note(text if len(srcs) == 1 else f"{len(srcs)} files: {text}")
    for name, how in ds.assumed.items():
        note(f"{name} is assumed, not measured ({how})")
    for name in ds.metadata.get("censored") or {}:
        total = sum((r.get("censored") or {}).get(name, {}).get("samples", 0)
                    for r in experiments)
        note(f"{name}: {total} raw samples at the declared clipping level are masked in "
             f"{name}_censored (1 = censored; the value kept is the sensor's limit)")
    quant, held, design = defaultdict(list), [], defaultdict(set)
    for r in experiments:
        for f in r["checks"]:
            if f.get("by_design") and f["kind"] in ("quantised", "held"):
                design[f["channel"]].add(f["by_design"])
            elif f["kind"] == "quantised":
                quant[f["channel"]].append(f["step"])
            elif f["kind"] == "gap":
                note(f"{r['source']}: {f['message']}")
            elif f["kind"] == "held" and len(srcs) == 1:
                held.append(f"{f['channel']} {f['side']} {f['level']:.4g} {f['unit']} "
                            f"({f['fraction']:.0%}, longest {f['longest_s']:.0f} s)")
    if design:
        note("held by design, not a sensor fault (levels held between changes): " + ", ".join(
            f"{ch} ({'; '.join(sorted(why))})" for ch, why in design.items()))
    if quant:
        of = "" if len(srcs) == 1 else " in {} of " + f"{len(experiments)} files"
        note("quantised sensors (few levels, held): " + ", ".join(
            f"{ch} step {min(st):.3g}"
            + (f"-{max(st):.3g}" if max(st) > min(st) * 1.01 else "")
            + f" {ds.units[ch]}" + of.format(len(st)) for ch, st in quant.items()))
    if held:
        note("at an extreme for long runs (a clipped sensor, a controlled limit or a steady "
             "value; censored_above/censored_below in the map masks a clipped one): "
             + ", ".join(held))
    for f in ds.metadata.get("censoring", []):
        if f["channel"] not in (ds.metadata.get("censored") or {}):
            note(f["message"])
