"""Figures a person can look at (paper Fig. 5-9), written as PNG files.

Every function builds a :class:`matplotlib.figure.Figure` without pyplot (no
display, no global state) and writes it atomically. Panels follow the paper:

* ``(a)`` the middle image (background shown at 230 instead of 255, as in
  the paper) and the difference images of each camera's outer frames;
* ``(b)`` normal-flow fields drawn as needles along the edge normals at the
  edge points (relative, stationary, moving);
* ``(c)`` the edge points whose depth could be determined;
* ``(d)`` recovered 3-D points projected on the Y-Z plane next to the truth.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

__all__ = [
    "save_figure",
    "image_panel",
    "difference_panel",
    "needle_panel",
    "edge_points_panel",
    "yz_projection_panel",
    "colormap_panel",
]


def save_figure(fig: Figure, path, *, dpi: int = 110) -> Path:
    """Write ``fig`` as PNG atomically, replacing ``path`` (:func:`nfdepth.io.atomic_write`: mode from the umask)."""
    from .io import atomic_write

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    return atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=dpi, bbox_inches="tight"), force=True)


def _figure(width_in=4.0, height_in=4.0) -> Figure:
    return Figure(figsize=(width_in, height_in), layout="constrained")


def image_panel(image, *, title: str, display_background: float | None = 230.0, background: float = 255.0) -> Figure:
    """The grey image; pixels at ``background`` drawn at ``display_background`` (paper)."""
    img = np.array(image, dtype=float)
    if display_background is not None:
        img[img == background] = display_background
    fig = _figure()
    ax = fig.add_subplot()
    ax.imshow(img, cmap="gray", vmin=0, vmax=255, interpolation="nearest")
    ax.set_title(title)
    ax.set_axis_off()
    return fig


def difference_panel(first, last, *, title: str, base: float = 230.0) -> Figure:
    """Difference image ``last - first`` drawn around a uniform ``base`` (paper Fig. 9a)."""
    diff = np.asarray(last, dtype=float) - np.asarray(first, dtype=float)
    fig = _figure()
    ax = fig.add_subplot()
    ax.imshow(np.clip(base - np.abs(diff), 0, 255), cmap="gray", vmin=0, vmax=255, interpolation="nearest")
    ax.set_title(title)
    ax.set_axis_off()
    return fig


def needle_panel(rows, cols, alpha, flow, *, shape, title: str, scale_px: float | None = None) -> Figure:
    """Normal flow as needles along ``(cos alpha, sin alpha)`` at each point.

    ``flow`` in px per unit time; needles are scaled so the longest is about
    6 px unless ``scale_px`` (drawn length per unit flow) is given.
    """
    flow = np.asarray(flow, dtype=float)
    ok = np.isfinite(flow)
    fig = _figure()
    ax = fig.add_subplot()
    if scale_px is None:
        peak = np.nanmax(np.abs(flow[ok])) if np.any(ok) else 1.0
        scale_px = 6.0 / peak if peak > 0 else 1.0
    dc = np.cos(alpha[ok]) * flow[ok] * scale_px
    dr = np.sin(alpha[ok]) * flow[ok] * scale_px
    ax.quiver(cols[ok], rows[ok], dc, dr, angles="xy", scale_units="xy", scale=1.0, width=0.003, headwidth=0, headlength=0, headaxislength=0, color="k")
    ax.set_xlim(0, shape[1])
    ax.set_ylim(shape[0], 0)
    ax.set_aspect("equal")
    ax.set_title(f"{title} (needle {scale_px:.3g} px per px/t)")
    return fig


def edge_points_panel(rows, cols, *, shape, title: str, valid=None) -> Figure:
    """Edge points (black) and, if ``valid`` given, refused ones (grey)."""
    fig = _figure()
    ax = fig.add_subplot()
    rows = np.asarray(rows)
    cols = np.asarray(cols)
    if valid is None:
        valid = np.ones(rows.shape, bool)
    ax.scatter(cols[~valid], rows[~valid], s=1, c="0.75", marker="s", linewidths=0, label="undeterminable")
    ax.scatter(cols[valid], rows[valid], s=1, c="k", marker="s", linewidths=0, label="depth determined")
    ax.set_xlim(0, shape[1])
    ax.set_ylim(shape[0], 0)
    ax.set_aspect("equal")
    ax.set_title(title)
    ax.legend(loc="lower right", fontsize=6, markerscale=4)
    return fig


def yz_projection_panel(points, *, true_points=None, title: str) -> Figure:
    """Recovered 3-D points projected on the Y-Z plane, with the truth in grey."""
    fig = _figure(5.0, 4.0)
    ax = fig.add_subplot()
    pts = np.asarray(points, dtype=float)
    ok = np.all(np.isfinite(pts), axis=1)
    if true_points is not None:
        tp = np.asarray(true_points, dtype=float)
        tok = np.all(np.isfinite(tp), axis=1)
        ax.scatter(tp[tok, 2], tp[tok, 1], s=2, c="0.7", linewidths=0, label="true")
    ax.scatter(pts[ok, 2], pts[ok, 1], s=2, c="tab:red", linewidths=0, label="recovered")
    ax.invert_yaxis()
    ax.set_xlabel("Z (depth)")
    ax.set_ylabel("Y (down)")
    ax.set_title(title)
    ax.legend(fontsize=7, markerscale=3)
    return fig


def colormap_panel(array, *, title: str, unit: str, cmap: str = "turbo", vmin=None, vmax=None) -> Figure:
    """A colour map with a colour bar in ``unit`` (NaN drawn black).

    ``cmap`` is a matplotlib colour-map name or a Colormap object.
    """
    arr = np.asarray(array, dtype=float)
    fig = _figure(5.5, 4.0)
    ax = fig.add_subplot()
    base = matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap
    colours = base.with_extremes(bad="black")
    finite = arr[np.isfinite(arr)]
    if vmin is None:
        vmin = float(np.percentile(finite, 1)) if finite.size else 0.0
    if vmax is None:
        vmax = float(np.percentile(finite, 99)) if finite.size else 1.0
    im = ax.imshow(np.ma.masked_invalid(arr), cmap=colours, vmin=vmin, vmax=vmax, interpolation="nearest")
    ax.set_title(title)
    ax.set_axis_off()
    fig.colorbar(im, ax=ax, label=unit, shrink=0.85)
    return fig
