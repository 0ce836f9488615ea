"""A short GIF of the transient: the top view's raster at each written time.

Frames are the metrics' raster coloured directly with numpy (no matplotlib per frame) and
the meniscus pixels darkened, so a 40-frame GIF costs a few seconds; the frames are thinned
to stay within a time budget, and the GIF is skipped when even that cannot be met.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from scipy import ndimage

from ehlfoam.run import fields as case_fields
from ehlfoam.metrics import pattern as flow

from ehlfoam.report import style

#: Most frames in a GIF.
MAX_FRAMES = 48
#: Wall-clock budget for the whole GIF [s].
BUDGET_S = 8.0


def colour_frame(r: flow.Raster) -> np.ndarray:
    """RGB uint8 image (rows top = +y) of a raster: oil colour map, island grey, the
    alpha = 0.5 boundary pixels black."""
    alpha = np.nan_to_num(r.alpha, nan=0.0)
    rgb = style.OIL_CMAP(alpha)[..., :3]
    oil = r.oil()
    edge = oil & ~ndimage.binary_erosion(oil)
    rgb[edge & ~r.island] = 0.0
    rgb[r.island] = style.ISLAND_RGB
    return (np.flipud(rgb) * 255).astype(np.uint8)


def _label(image: np.ndarray, text: str):
    from PIL import Image, ImageDraw

    im = Image.fromarray(image)
    draw = ImageDraw.Draw(im)
    draw.rectangle((2, 2, 8 + 6 * len(text), 16), fill=(255, 255, 255))
    draw.text((5, 4), text, fill=(0, 0, 0))
    # a small palette without dithering: flat colours compress well in a GIF
    return im.quantize(colors=48, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)


def written_pattern(folder: Path, geom, structure: case_fields.Structure
                    ) -> tuple[flow.Raster, dict]:
    """The top view's raster of one written time of a 3D case (its mid-gap oil fraction) and
    the flow pattern the metrics read from it."""
    mid = case_fields.mid_gap_alpha(folder, structure, geom)
    r = case_fields.column_raster(mid, structure, geom)
    return r, flow.flow_pattern_from_raster(r)


def _frame(folder: Path, t: float, geom, structure: case_fields.Structure):
    r, pattern = written_pattern(folder, geom, structure)
    state = pattern["state"]
    text = f"t = {t * 1e3:.1f} ms  ({t / geom.transit_time:.2f} transits)  state {state}"
    return _label(colour_frame(r), text)


def make_gif(case: Path, geom, structure: case_fields.Structure, out: Path,
             budget_s: float = BUDGET_S, max_frames: int = MAX_FRAMES) -> Path | None:
    """Write ``out`` (GIF) of the written times of ``case``: as many frames, evenly spread,
    as the first frame's cost lets fit in ``budget_s`` [s] (at most ``max_frames``). None
    when fewer than 2 times were written or fewer than 4 frames would fit."""
    folders = case_fields.time_folders(case)
    if len(folders) < 2:
        return None
    start = time.monotonic()
    try:
        first = _frame(folders[0][1], folders[0][0], geom, structure)
    except Exception:
        return None
    cost = time.monotonic() - start
    n = int(min(max_frames, len(folders), budget_s / max(cost, 1e-3)))
    if n < 4 and len(folders) >= 4:
        return None
    pick = np.unique(np.linspace(0, len(folders) - 1, max(n, 2)).round().astype(int))
    frames = [first]
    for k in pick[1:]:
        t, folder = folders[k]
        try:
            frames.append(_frame(folder, t, geom, structure))
        except Exception:   # a folder being written, or a broken one: skip the frame
            continue
        if time.monotonic() - start > 1.5 * budget_s:
            break
    if len(frames) < 2:
        return None
    frames[0].save(out, save_all=True, append_images=frames[1:], duration=150, loop=0)
    return Path(out)
