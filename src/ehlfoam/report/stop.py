"""The sudden stop's pictures: a thin-film run with a ``[stop]`` keeps its state every
``stop.frame_interval`` in ``DIR/frames/`` (:mod:`ehlfoam.run.thin_film`), a 3D run writes
its fields ``run.writes_per_transit`` times a transit; this draws each frame (a kept state
or a written time) as the top view's raster (the metrics' own, as
:mod:`ehlfoam.report.animation` draws a 3D case's written times), labelled with the time
from the stop, the walls' speed (:func:`~ehlfoam.spec.stop.wall_speed_at`) and what the
metrics read (state, bubble, the region's length and width), into a GIF and a strip of six
frames (PNG), and lists each frame's reading (:func:`stop_frames`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ehlfoam.case.geometry import CaseGeometry
from ehlfoam.report.animation import _label, colour_frame, written_pattern
from ehlfoam.report.thin_film import ThinFilmFields
from ehlfoam.run.thin_film import FRAMES_DIR
from ehlfoam.spec.stop import Stop, wall_speed_at
from ehlfoam.thinfilm.state import load_state

__all__ = ["make_stop_pictures", "stop_frames"]

#: Most frames in the GIF (every frame up to it, evenly thinned beyond).
MAX_FRAMES = 80
#: The strip's frames: the time from the start of the stop [s].
STRIP_TIMES = (-0.005, 0.005, 0.015, 0.035, 0.055, 0.105)


def _frame_files(case: Path) -> list[Path]:
    return sorted((Path(case) / FRAMES_DIR).glob("[0-9][0-9][0-9][0-9].npz"))


def _thin_film_frames(case: Path, geom: CaseGeometry):
    """(run time [s], raster, pattern, enclosed gas pockets, their cells) of each state a
    thin-film run kept in ``DIR/frames/``."""
    from scipy import ndimage

    for f in _frame_files(case):
        sol = load_state(f)
        fields = ThinFilmFields(time=sol.time, folder=f, geom=geom, sol=sol)
        cav = np.zeros(sol.flooded.shape, bool) if sol.cavity is None else sol.cavity
        yield (sol.time, fields.raster, fields.pattern, int(ndimage.label(cav)[1]),
               int(cav.sum()))


def _written_frames(case: Path, geom: CaseGeometry):
    """The same of each time a 3D run wrote: the enclosed bubbles the metrics count, the
    raster's pixels of enclosed gas not counted (None)."""
    from ehlfoam.run import fields as case_fields

    structure = case_fields.Structure.load(case)
    for t, folder in case_fields.time_folders(case):
        raster, pattern = written_pattern(folder, geom, structure)
        yield t, raster, pattern, int(pattern.get("enclosed_bubbles") or 0), None


def stop_frames(case: str | Path, geom: CaseGeometry, stop: Stop, speed: float,
                written: bool = False) -> list[dict]:
    """Each frame's reading: ``time_s`` (run time), ``from_stop_s`` (time from the start of
    the deceleration), ``wall_speed_m_s``, the metrics' ``state``,
    ``bubble_length_over_a``, ``bubble_enclosed``, ``flooded_length_over_a``,
    ``flooded_width_over_a``, ``cavities`` (the enclosed gas pockets) and ``cavity_cells``
    (their cells; None for a 3D run). The frames: the states a thin-film run kept, or with
    ``written`` a 3D run's written times."""
    frames = (_written_frames if written else _thin_film_frames)(Path(case), geom)
    out = []
    for t, raster, p, pockets, cells in frames:
        out.append({"time_s": t, "from_stop_s": t - (stop.at or 0.0),
                    "wall_speed_m_s": float(wall_speed_at(stop, speed, t)),
                    "state": p.get("state"),
                    "bubble_length_over_a": p.get("bubble_length_over_a"),
                    "bubble_enclosed": p.get("bubble_enclosed"),
                    "flooded_length_over_a": p.get("flooded_length_over_a"),
                    "flooded_width_over_a": p.get("flooded_width_over_a"),
                    "cavities": pockets, "cavity_cells": cells, "_raster": raster})
    return out


def _image(rec: dict):
    r = rec["_raster"]
    bub = rec["bubble_length_over_a"]
    text = (f"{rec['from_stop_s'] * 1e3:+6.1f} ms from the stop  u = "
            f"{rec['wall_speed_m_s'] * 1e3:.2f} mm/s  state {rec['state']}  bubble "
            f"{'-' if bub is None else f'{bub:.2f} a'}  region "
            f"{rec['flooded_length_over_a'] or 0:.1f} x {rec['flooded_width_over_a'] or 0:.1f} a")
    return _label(colour_frame(r), text)


def make_stop_pictures(case: str | Path, geom: CaseGeometry, stop: Stop, speed: float,
                       out: str | Path, written: bool = False
                       ) -> tuple[Path | None, Path | None, list[dict]]:
    """``out/stop.gif`` (every frame, thinned evenly to :data:`MAX_FRAMES`) and
    ``out/stop_frames.png`` (the frames nearest :data:`STRIP_TIMES` from the stop, side by
    side in two rows) of the stopping run in ``case``, and each frame's reading
    (:func:`stop_frames`, without the rasters; ``written``: a 3D run's written times).
    (None, None, []) without frames."""
    from PIL import Image

    out = Path(out)
    recs = stop_frames(case, geom, stop, speed, written)
    if len(recs) < 2:
        return None, None, [{k: v for k, v in r.items() if k != "_raster"} for r in recs]
    pick = np.unique(np.linspace(0, len(recs) - 1, min(MAX_FRAMES, len(recs))).round()
                     .astype(int))
    frames = [_image(recs[k]) for k in pick]
    gif = out / "stop.gif"
    frames[0].save(gif, save_all=True, append_images=frames[1:], duration=120, loop=0)
    times = np.array([r["from_stop_s"] for r in recs])
    chosen = sorted({int(np.argmin(np.abs(times - t))) for t in STRIP_TIMES})
    tiles = [_image(recs[k]).convert("RGB") for k in chosen]
    w, h = tiles[0].size
    cols = (len(tiles) + 1) // 2
    sheet = Image.new("RGB", (cols * w, 2 * h if len(tiles) > 1 else h), (255, 255, 255))
    for i, tile in enumerate(tiles):
        sheet.paste(tile, ((i % cols) * w, (i // cols) * h))
    png = out / "stop_frames.png"
    sheet.save(png)
    return gif, png, [{k: v for k, v in r.items() if k != "_raster"} for r in recs]
