"""Figures a stage writes for the report: the PNG, its caption and its line-visibility audit.

A stage saves each figure with :func:`save_report_figure`, which checks that every labelled
line is visible (:mod:`acid.report.audit`) before writing the PNG, and lists them in its
folder's ``figures.json`` (:func:`write_figure_index`). The report reads that index
(:func:`read_figure_index`), so captions travel with the figures and a hidden line shows up
in the report and fails its checks, whichever engineer's figure it is.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from acid._io import save_figure, write_json
from acid.report.audit import audit_figure

FIGURE_INDEX = "figures.json"
#: resolution of the saved PNGs (and of the visibility audit), dots per inch
FIGURE_DPI = 120


@dataclass(frozen=True)
class FigureRecord:
    """A figure of a stage: PNG file name (in the stage folder), caption, audit results.

    ``labelled_lines`` lines were checked; ``hidden`` names those (``"axes: label"``) that
    keep less than the audit's minimum share of their pixels visible.
    """

    file: str
    caption: str
    labelled_lines: int
    hidden: tuple[str, ...] = ()

    def to_json_dict(self) -> dict:
        return {"file": self.file, "caption": self.caption,
                "labelled_lines": self.labelled_lines, "hidden": list(self.hidden)}

    @classmethod
    def from_json_dict(cls, d: dict) -> FigureRecord:
        return cls(file=str(d["file"]), caption=str(d["caption"]),
                   labelled_lines=int(d.get("labelled_lines", 0)),
                   hidden=tuple(str(h) for h in d.get("hidden", ())))


def save_report_figure(fig, folder: Path, stem: str, caption: str) -> FigureRecord:
    """Audit ``fig`` for hidden lines, save it as ``folder/stem.png``; its record."""
    audit = audit_figure(fig, dpi=FIGURE_DPI)
    save_figure(fig, Path(folder) / f"{stem}.png", dpi=FIGURE_DPI)
    return FigureRecord(file=f"{stem}.png", caption=caption, labelled_lines=len(audit.lines),
                        hidden=tuple(f"{h.axes}: {h.label}" for h in audit.hidden))


def write_figure_index(folder: Path, records: list[FigureRecord]) -> Path:
    """Write ``folder/figures.json`` listing the stage's figures in report order."""
    return write_json(Path(folder) / FIGURE_INDEX, [r.to_json_dict() for r in records])


def read_figure_index(folder: Path) -> list[FigureRecord]:
    """The figures a stage listed (empty when it wrote none)."""
    path = Path(folder) / FIGURE_INDEX
    if not path.is_file():
        return []
    return [FigureRecord.from_json_dict(d) for d in json.loads(path.read_text())]
