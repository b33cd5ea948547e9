"""Writing a figure: make the folder, save atomically (never half a file, :mod:`tooltransfer.atomic`),
close (no display is needed anywhere)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tooltransfer.atomic import atomic_path


def save_figure(fig: Any, out: str | Path, dpi: int = 120) -> Path:
    """Save the matplotlib figure ``fig`` to ``out`` (format from the suffix), close it, return the path.

    The saved area is the figure's drawn content with a small pad (``bbox_inches="tight"``): the axes'
    labels are never cut off, whatever the panels' aspect ratios left of the figure's size."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    path = Path(out)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, bbox_inches="tight", pad_inches=0.05)
    finally:
        plt.close(fig)
    return path
