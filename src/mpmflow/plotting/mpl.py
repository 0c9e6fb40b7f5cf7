"""The one way mpmflow uses matplotlib (an optional extra): the non-interactive pyplot, with
a clear error when matplotlib is missing, and an atomic PNG save."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

from ..errors import CaseError
from ..output.atomic import atomic_path

if TYPE_CHECKING:  # matplotlib is an optional extra: imported when a figure is made
    from matplotlib.figure import Figure


def pyplot(needs: str = "mpmflow plot") -> ModuleType:
    """matplotlib.pyplot with the Agg backend; CaseError (exit 2) saying ``needs`` needs
    matplotlib and how to install it when it is missing."""
    try:
        import matplotlib
    except ImportError:
        raise CaseError(
            f"{needs} needs matplotlib: pip install 'mpmflow[plot]' (or pip install matplotlib)."
        ) from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def have_matplotlib(needs: str) -> None:
    """Check up front that matplotlib can be imported (the CaseError of ``pyplot``)."""
    pyplot(needs)


def save(fig: Figure, path: str | Path, dpi: float) -> None:
    """Save a figure as PNG atomically (at ``dpi``) and close it."""
    import matplotlib.pyplot as plt

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    plt.close(fig)
