"""Result tables written three ways: Markdown (to read), CSV (to compute with), LaTeX (to publish).

A :class:`Table` holds rows of raw values and column descriptions (header, unit, number
format). CSV keeps full precision; Markdown and LaTeX show the formatted numbers, LaTeX with
booktabs rules and powers of ten as ``$1.2\\times10^{-11}$``. Missing values (None, NaN) are
empty in CSV and a dash elsewhere.
"""

from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from biped_sim.io.atomic import write_text_atomic

LATEX_SPECIALS = {
    "\\": r"\textbackslash{}",
    "&": r"\&",
    "%": r"\%",
    "$": r"\$",
    "#": r"\#",
    "_": r"\_",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
}
_EXPONENT = re.compile(r"^([-+]?\d+(?:\.\d+)?)e([-+]?)0*(\d+)$")


@dataclass(frozen=True)
class Column:
    """One column: the row key, its header, its unit and how numbers are shown (a format spec)."""

    key: str
    header: str
    unit: str = ""
    fmt: str = ""

    @property
    def title(self) -> str:
        return f"{self.header} [{self.unit}]" if self.unit else self.header


def is_missing(value: Any) -> bool:
    """None or NaN."""
    return value is None or (isinstance(value, float) and math.isnan(value))


def format_value(value: Any, fmt: str) -> str:
    """A value as text with ``fmt`` (numbers only; text is shown as is); '' when missing."""
    if is_missing(value):
        return ""
    if fmt and isinstance(value, int | float) and not isinstance(value, bool):
        if fmt.endswith("d") and isinstance(value, float):
            # an integer counter read from a column with gaps is a float: 34.0 is shown as 34
            return format(int(value), fmt) if value.is_integer() else format(value, "g")
        return format(value, fmt)
    return str(value)


def latex_escape(text: str) -> str:
    """Escape LaTeX's special characters."""
    return "".join(LATEX_SPECIALS.get(ch, ch) for ch in text)


def latex_cell(text: str) -> str:
    """A formatted cell for LaTeX: '1.2e-11' becomes $1.2\\times10^{-11}$, text is escaped."""
    match = _EXPONENT.match(text)
    if match:
        mantissa, sign, exponent = match.groups()
        exponent = f"{'-' if sign == '-' else ''}{exponent}"
        return rf"${mantissa}\times10^{{{exponent}}}$"
    return latex_escape(text)


@dataclass
class Table:
    """A titled table with notes; written as name.md, name.csv and name.tex."""

    name: str
    title: str
    columns: list[Column]
    rows: list[dict[str, Any]]
    notes: list[str] = field(default_factory=list)

    def cells(self) -> list[list[str]]:
        """Formatted cells (dash for missing)."""
        return [[format_value(row.get(c.key), c.fmt) or "–" for c in self.columns] for row in self.rows]

    def _numeric(self, column: Column) -> bool:
        values = [row.get(column.key) for row in self.rows if not is_missing(row.get(column.key))]
        return bool(values) and all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)

    def markdown(self, heading_level: int = 3) -> str:
        """A Markdown section: heading, pipe table, notes."""
        lines = [f"{'#' * heading_level} {self.title}", ""]
        lines.append("| " + " | ".join(c.title.replace("|", "\\|") for c in self.columns) + " |")
        lines.append("|" + "|".join("---:" if self._numeric(c) else ":---" for c in self.columns) + "|")
        for cells in self.cells():
            lines.append("| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |")
        if self.notes:
            lines.append("")
            lines.extend(f"- {note}" for note in self.notes)
        return "\n".join(lines) + "\n"

    def csv(self) -> str:
        """CSV with full-precision numbers and 'header [unit]' column titles."""
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow([c.title for c in self.columns])
        for row in self.rows:
            writer.writerow(["" if is_missing(row.get(c.key)) else row.get(c.key) for c in self.columns])
        return buffer.getvalue()

    def latex(self) -> str:
        """A booktabs ``table`` environment with caption, label and notes below."""
        align = "".join("r" if self._numeric(c) else "l" for c in self.columns)
        header = " & ".join(
            latex_escape(c.header) + (f" [{latex_escape(c.unit)}]" if c.unit else "") for c in self.columns
        )
        lines = [
            r"\begin{table}[htbp]",
            r"\centering",
            rf"\caption{{{latex_escape(self.title)}}}",
            rf"\label{{tab:{self.name.replace('_', '-')}}}",
            rf"\begin{{tabular}}{{{align}}}",
            r"\toprule",
            header + r" \\",
            r"\midrule",
        ]
        for cells in self.cells():
            lines.append(" & ".join("--" if cell == "–" else latex_cell(cell) for cell in cells) + r" \\")
        lines += [r"\bottomrule", r"\end{tabular}"]
        if self.notes:
            lines.append(r"\par\smallskip\footnotesize " + " ".join(latex_escape(n) for n in self.notes))
        lines.append(r"\end{table}")
        return "\n".join(lines) + "\n"

    def write(self, out_dir: Path) -> list[Path]:
        """Write name.md, name.csv and name.tex into ``out_dir`` (atomically)."""
        paths = []
        for suffix, text in ((".md", self.markdown()), (".csv", self.csv()), (".tex", self.latex())):
            path = out_dir / f"{self.name}{suffix}"
            write_text_atomic(path, text)
            paths.append(path)
        return paths
