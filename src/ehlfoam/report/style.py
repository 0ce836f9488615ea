"""Colours, colour maps and figure helpers shared by the report's pictures.

Matplotlib is used through :class:`matplotlib.figure.Figure` and the Agg canvas only (no
pyplot, no display): safe off-screen and in worker processes.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg", force=False)

from matplotlib.colors import LinearSegmentedColormap  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

#: Air (oil fraction 0) and oil (oil fraction 1) as RGB in [0, 1]: a light, cool air and a
#: dark amber oil, monotone in lightness so that a grey-scale print still reads.
AIR_RGB = (0.945, 0.957, 0.972)
OIL_RGB = (0.545, 0.298, 0.067)
OIL_CMAP = LinearSegmentedColormap.from_list(
    "ehl_oil", [AIR_RGB, (0.929, 0.808, 0.549), (0.776, 0.518, 0.192), OIL_RGB])
#: The island (the unmeshed Hertzian contact and its rim).
ISLAND_RGB = (0.62, 0.64, 0.66)
#: The alpha = 0.5 meniscus line.
MENISCUS_RGB = (0.0, 0.0, 0.0)
#: Bubble (gas at the contact exit) outline and fill.
BUBBLE_RGB = (0.80, 0.10, 0.12)
#: State label colours.
STATE_RGB = {"I": (0.13, 0.47, 0.22), "II": (0.75, 0.18, 0.10)}
#: Default resolution of the report PNGs [dots per inch].
DPI = 110


def new_figure(width_in: float, height_in: float, dpi: int = DPI) -> Figure:
    """An Agg-backed figure of the given size [inches]."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = Figure(figsize=(width_in, height_in), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def save(fig: Figure, path: Path) -> Path:
    """Write the figure as PNG at its own dpi (no tight bounding box: pixel positions of the
    data stay where :func:`data_to_pixel` says)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=fig.dpi, facecolor="white")
    return path


def data_to_pixel(fig: Figure, ax, draw: bool = True) -> list[float]:
    """[sx, ox, sy, oy]: PNG column = ox + sx * x, row = oy - sy * y for data (x, y) of
    ``ax`` (linear axes) in the PNG :func:`save` writes (call it after :func:`save`, or
    before with ``draw=True``: the axes box settles only when the figure is drawn)."""
    if draw:
        fig.canvas.draw()
    (x0, y0), (x1, y1) = ax.transData.transform([(0.0, 0.0), (1.0, 1.0)])
    height = fig.get_size_inches()[1] * fig.dpi
    return [float(x1 - x0), float(x0), float(y1 - y0), float(height - y0)]


def nice_length(span: float, fraction: float = 0.2) -> float:
    """A round length (1, 2 or 5 x 10^k) near ``fraction`` of ``span``."""
    import math

    target = span * fraction
    k = math.floor(math.log10(target))
    for m in (5.0, 2.0, 1.0):
        if m * 10**k <= target:
            return m * 10**k
    return 10**k
