"""The deformed gap h(x, y) between ball and disc, in metres, anywhere around the contact.

    h = h0 + (R - sqrt(R^2 - r^2)) + w(x, y)

with the rigid sphere, the elastic deformation w of the computed pressure and the film
constant h0. Inside the EHL domain the solver's own film is used (its paraboloid swapped
for the exact sphere); outside, w is summed directly from the pressure, coarsened to
cells of 1/64 of the domain height and treated as point loads (error ~ (cell/r)^2 / 24).
Over a band of 0.25 a inside the domain edge the two are blended smoothly, so h is
continuous everywhere. This is what the mesh generator calls.
"""

from __future__ import annotations

from collections import OrderedDict
from pathlib import Path

import numpy as np
from numba import njit, prange
from scipy.interpolate import RegularGridInterpolator

from ehlfoam.contact.elastic import ELASTIC_PREFACTOR

BLEND_BAND = 0.25  # units of a
FAR_CELLS = 64  # coarse cells across the domain height


#: query points summed together: the inner loop runs over them, so it vectorises, while
#: each point's sum keeps its order over the sources (the same bits as a loop per point)
_BLOCK = 256


@njit(parallel=True, cache=True)
def _point_loads(xq, yq, xc, yc, q, out):
    """out[k] = sum over m of q[m] / |(xq[k], yq[k]) - (xc[m], yc[m])|, in blocks of query
    points (padding at infinity adds nothing)."""
    n = xq.shape[0]
    for b in prange((n + _BLOCK - 1) // _BLOCK):
        k0 = b * _BLOCK
        w = min(_BLOCK, n - k0)
        bx = np.full(_BLOCK, np.inf)
        by = np.full(_BLOCK, np.inf)
        bx[:w] = xq[k0:k0 + w]
        by[:w] = yq[k0:k0 + w]
        acc = np.zeros(_BLOCK)
        for m in range(xc.shape[0]):
            xm, ym, qm = xc[m], yc[m], q[m]
            for k in range(_BLOCK):
                dx = bx[k] - xm
                dy = by[k] - ym
                acc[k] += qm / np.sqrt(dx * dx + dy * dy)
        out[k0:k0 + w] = acc[:w]


#: how many gap fields :meth:`GapField.load` keeps in memory, and them by file identity
_KEEP = 4
_LOADED: OrderedDict[tuple[int, int, int, int], "GapField"] = OrderedDict()


class GapField:
    """h(x, y) [m] of a solved contact; x along rolling, origin at the contact centre.

    Args:
        x, y: grid coordinates of the solution (units of a).
        P: dimensionless pressure on the grid (units pH).
        H: dimensionless film on the grid (units a^2/R), paraboloid rigid term.
        H0: dimensionless film constant.
        a: Hertzian radius [m].
        radius: ball radius R [m].
    """

    def __init__(self, x, y, P, H, H0: float, a: float, radius: float):
        self.a, self.R, self.H0 = a, radius, H0
        self.scale = a * a / radius
        self.x, self.y = np.asarray(x), np.asarray(y)
        self._interp = RegularGridInterpolator((self.y, self.x), np.asarray(H))
        h = self.x[1] - self.x[0]
        b = max(1, (len(self.y) - 1) // FAR_CELLS)
        ny, nx = (len(self.y) - 1) // b, (len(self.x) - 1) // b
        Pc = np.asarray(P)[: ny * b, : nx * b].reshape(ny, b, nx, b).sum(axis=(1, 3))
        xc = self.x[: nx * b].reshape(nx, b).mean(axis=1)
        yc = self.y[: ny * b].reshape(ny, b).mean(axis=1)
        Xc, Yc = np.meshgrid(xc, yc)
        keep = Pc != 0.0
        self._xc, self._yc = Xc[keep].ravel(), Yc[keep].ravel()
        self._q = ELASTIC_PREFACTOR * h * h * Pc[keep].ravel()

    @classmethod
    def from_result(cls, result) -> "GapField":
        """From a :class:`~ehlfoam.contact.solver.PrecalcResult`."""
        mg = result.mg
        return cls(mg.x, mg.y, mg.P, mg.H, mg.H0, result.contact.a, result.contact.radius)

    @classmethod
    def load(cls, directory: str | Path) -> "GapField":
        """From a precalc output folder (``solution.npz``). The last few read are kept in
        memory by the file's identity (device, inode, size and time), so a case written
        and run in one process (a batch's worker), whose precalc is a hard link to the
        cache's (:func:`ehlfoam._io.link_tree`), reads it once."""
        path = Path(directory) / "solution.npz"
        st = path.stat()
        key = (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)
        if key not in _LOADED:
            _LOADED[key] = cls._read(path)
            while len(_LOADED) > _KEEP:
                _LOADED.popitem(last=False)
        _LOADED.move_to_end(key)
        return _LOADED[key]

    @classmethod
    def _read(cls, path: Path) -> "GapField":
        d = np.load(path)
        a = float(d["a_m"])
        R = float(d["radius_m"])
        scale = a * a / R
        return cls(d["x"] / a, d["y"] / a, d["p"] / float(d["p_hertz_Pa"]), d["h"] / scale,
                   float(d["h0_m"]) / scale, a, R)

    def _sphere(self, X, Y):
        r2 = (X * X + Y * Y) * self.a**2
        if np.any(r2 >= self.R**2):
            raise ValueError(f"gap requested at r >= R = {self.R} m: outside the ball")
        return (self.R - np.sqrt(self.R**2 - r2)) / self.scale

    def far(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """Dimensionless deformation from the coarsened pressure at points (X, Y) (units a)."""
        out = np.empty(X.size)
        _point_loads(np.ascontiguousarray(X.ravel(), dtype=float),
                     np.ascontiguousarray(Y.ravel(), dtype=float), self._xc, self._yc, self._q, out)
        return out.reshape(X.shape)

    def __call__(self, x_m, y_m) -> np.ndarray:
        """Gap h [m] at points x_m, y_m [m] (broadcastable arrays)."""
        X, Y = np.broadcast_arrays(np.asarray(x_m, float) / self.a, np.asarray(y_m, float) / self.a)
        sphere = self._sphere(X, Y)
        # distance inside the domain edge (negative outside)
        d = np.minimum.reduce([X - self.x[0], self.x[-1] - X, Y - self.y[0], self.y[-1] - Y])
        w = np.clip(d / BLEND_BAND, 0.0, 1.0)
        w = w * w * (3.0 - 2.0 * w)
        H = np.zeros(X.shape)
        outer = w < 1.0
        if np.any(outer):
            H[outer] = self.H0 + sphere[outer] + self.far(X[outer], Y[outer])
        inner = w > 0.0
        if np.any(inner):
            Xi, Yi = X[inner], Y[inner]
            h_in = (self._interp(np.column_stack([Yi, Xi])) - 0.5 * (Xi**2 + Yi**2)
                    + sphere[inner])
            H[inner] = w[inner] * h_in + (1.0 - w[inner]) * H[inner]
        return H * self.scale
