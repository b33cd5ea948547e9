"""Writing a figure: make the folder, save, close (no display is needed anywhere)."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def save_figure(fig: Any, out: str | Path, dpi: int = 120) -> Path:
    """Save the matplotlib figure ``fig`` to ``out`` (format from the suffix), close it, return the path."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
