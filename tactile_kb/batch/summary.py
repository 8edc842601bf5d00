"""Counts over result rows: answers, errors per kind, the confusion matrix, and the report."""

from __future__ import annotations

import io
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tactile_kb.files import atomic_write


@dataclass
class BatchSummary:
    """Counts over result rows: answers, errors per kind, and expected × answered labels."""

    rows: int = 0
    answers: Counter[str] = field(default_factory=Counter)
    errors: Counter[str] = field(default_factory=Counter)
    confusion: Counter[tuple[str, str]] = field(default_factory=Counter)
    """(expected label, answered label or ``"error"``) → count, for rows with a label."""

    def add(self, row: Mapping[str, Any]) -> None:
        """Count one row."""
        self.rows += 1
        error = row.get("error")
        if isinstance(error, dict):
            self.errors[str(error.get("kind"))] += 1
            answered = "error"
        else:
            self.answers[str(row.get("answer"))] += 1
            answered = str(row.get("label"))
        expected = row.get("expected")
        if expected is not None:
            self.confusion[(str(expected), answered)] += 1

    @property
    def labelled(self) -> bool:
        """Whether any row carried an expected label."""
        return bool(self.confusion)

    def classes(self) -> tuple[list[str], list[str]]:
        """The expected labels (rows) and the answered labels (columns; ``error`` last)."""
        expected = sorted({e for e, _ in self.confusion})
        answered = sorted({a for _, a in self.confusion if a != "error"} | set(expected))
        if any(a == "error" for _, a in self.confusion):
            answered.append("error")
        return expected, answered

    def accuracy(self) -> dict[str, tuple[int, int]]:
        """Per expected label: (answered right, total)."""
        out: dict[str, tuple[int, int]] = {}
        for (expected, answered), n in self.confusion.items():
            right, total = out.get(expected, (0, 0))
            out[expected] = (right + (n if answered == expected else 0), total + n)
        return dict(sorted(out.items()))

    def lines(self) -> list[str]:
        """The summary as text lines: counts, answers, errors, confusion matrix, accuracy."""
        errors = sum(self.errors.values())
        out = [f"{self.rows} results: {self.rows - errors} answered, {errors} failed"]
        if self.answers:
            out.append("answers:")
            width = max(len(a) for a in self.answers)
            out += [f"  {a:<{width}}  {n:>6}" for a, n in sorted(self.answers.items())]
        if self.errors:
            out.append("errors:")
            width = max(len(k) for k in self.errors)
            out += [f"  {k:<{width}}  {n:>6}" for k, n in sorted(self.errors.items())]
        if self.labelled:
            expected, answered = self.classes()
            head = max(len("expected"), *(len(e) for e in expected))
            widths = [max(len(a), 3) for a in answered]
            out.append("confusion matrix (rows: expected label, columns: answered label):")
            out.append(
                "  "
                + " " * head
                + "".join(f"  {a:>{w}}" for a, w in zip(answered, widths, strict=True))
            )
            for e in expected:
                cells = "".join(
                    f"  {self.confusion.get((e, a), 0):>{w}}"
                    for a, w in zip(answered, widths, strict=True)
                )
                out.append(f"  {e:<{head}}{cells}")
            out.append("accuracy per class:")
            right_all = total_all = 0
            for e, (right, total) in self.accuracy().items():
                right_all += right
                total_all += total
                out.append(f"  {e:<{head}}  {right:>6} of {total:<6} {100 * right / total:5.1f} %")
            out.append(
                f"  {'all':<{head}}  {right_all:>6} of {total_all:<6} "
                f"{100 * right_all / total_all:5.1f} %"
            )
        return out

    def plot_confusion(self, path: str | Path | io.BytesIO) -> None:
        """Draw the confusion matrix (counts, each row shaded by its share) to a PNG or SVG."""
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
        import numpy as np

        expected, answered = self.classes()
        counts = np.array(
            [[self.confusion.get((e, a), 0) for a in answered] for e in expected], dtype=float
        )
        share = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)
        width = max(6.0, 2.5 + 1.0 * len(answered) + 0.09 * max(len(e) for e in expected))
        height = max(3.5, 1.8 + 0.6 * len(expected) + 0.07 * max(len(a) for a in answered))
        fig, ax = plt.subplots(figsize=(width, height), dpi=120)
        try:
            image = ax.imshow(share, cmap="Blues", vmin=0, vmax=1, aspect="auto")
            bar = fig.colorbar(image, ax=ax, fraction=0.05, pad=0.03)
            bar.set_label("share of the row", fontsize=10)
            for i in range(len(expected)):
                for j in range(len(answered)):
                    n = int(counts[i, j])
                    if n:
                        ax.text(
                            j,
                            i,
                            str(n),
                            ha="center",
                            va="center",
                            fontsize=11,
                            color="white" if share[i, j] > 0.6 else "black",
                        )
            ax.set_xticks(range(len(answered)), answered, rotation=35, ha="right", fontsize=10)
            ax.set_yticks(range(len(expected)), expected, fontsize=10)
            ax.set_xlabel("answered label", fontsize=11)
            ax.set_ylabel("expected label", fontsize=11)
            right = sum(r for r, _ in self.accuracy().values())
            total = sum(t for _, t in self.accuracy().values())
            ax.set_title(
                f"Confusion matrix: {right} of {total} right ({100 * right / total:.1f} %)",
                fontsize=12,
            )
            fig.tight_layout()
            if isinstance(path, io.BytesIO):
                fig.savefig(path, format="png")
            else:  # atomically: a kill or a full disk leaves any earlier picture as it was
                fmt = Path(path).suffix.lstrip(".").lower() or "png"
                atomic_write(path, lambda f: fig.savefig(f, format=fmt))
        finally:
            plt.close(fig)

    def write_report(self, path: str | Path, *, title: str = "tactile-kb batch") -> None:
        """A Markdown or HTML report (by the suffix) with the matrix drawn beside it.

        Markdown links a PNG written next to it (``NAME-confusion.png``); HTML embeds it.
        """
        import base64
        import html

        p = Path(path)
        text = "\n".join(self.lines())
        if p.suffix.lower() in (".html", ".htm"):
            image = ""
            if self.labelled:
                buffer = io.BytesIO()
                self.plot_confusion(buffer)
                data = base64.b64encode(buffer.getvalue()).decode("ascii")
                image = f'<img alt="confusion matrix" src="data:image/png;base64,{data}">\n'
            body = (
                f'<!doctype html>\n<html><head><meta charset="utf-8"><title>{html.escape(title)}'
                f"</title></head><body>\n<h1>{html.escape(title)}</h1>\n{image}"
                f"<pre>{html.escape(text)}</pre>\n</body></html>\n"
            )
        else:
            image = ""
            if self.labelled:
                picture = p.with_name(p.stem + "-confusion.png")
                self.plot_confusion(picture)
                image = f"![confusion matrix]({picture.name})\n\n"
            body = f"# {title}\n\n{image}```text\n{text}\n```\n"
        atomic_write(p, lambda f: f.write(body.encode("utf-8")))
