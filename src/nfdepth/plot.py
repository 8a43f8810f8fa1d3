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
    "needle_scale_px",
    "edge_points_panel",
    "yz_projection_panel",
    "colormap_panel",
]


def save_figure(fig: Figure, path, *, dpi: int = 110, force: bool = True) -> Path:
    """Write ``fig`` as PNG atomically (:func:`nfdepth.io.atomic_write`: mode from the umask); an existing ``path`` is replaced unless ``force=False``.

    Missing folders of ``path`` are made (:func:`nfdepth.io.make_output_folder`: a failed or interrupted command-line run removes them again).
    """
    from ._validate import as_path
    from .io import atomic_write, make_output_folder

    path = as_path("path", path)
    make_output_folder(path.parent, parents=True)
    FigureCanvasAgg(fig)
    return atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=dpi, bbox_inches="tight"), force=force)


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


def difference_panel(first, last, *, title: str) -> Figure:
    """Difference image ``last - first`` (paper Fig. 9a), signed: a diverging colour map around 0 with its scale in grey levels.

    The paper prints ``230 - |difference|``, which loses the sign; here
    brightening and darkening are told apart, and the colour bar gives the
    size.
    """
    diff = np.asarray(last, dtype=float) - np.asarray(first, dtype=float)
    peak = float(np.max(np.abs(diff))) if diff.size else 0.0
    peak = peak if peak > 0 else 1.0
    fig = _figure(4.8, 4.0)
    ax = fig.add_subplot()
    im = ax.imshow(diff, cmap="RdBu_r", vmin=-peak, vmax=peak, interpolation="nearest")
    ax.set_title(title)
    ax.set_axis_off()
    fig.colorbar(im, ax=ax, label="difference (grey levels)", shrink=0.85)
    return fig


def needle_scale_px(*flows) -> float:
    """One needle scale for several normal-flow fields (drawn length per unit flow): the longest needle of all about 6 px."""
    peaks = [np.nanmax(np.abs(f)) for f in (np.asarray(f, dtype=float) for f in flows) if np.isfinite(f).any()]
    peak = max(peaks, default=0.0)
    return 6.0 / peak if peak > 0 else 1.0


def _image_axes(ax, shape) -> None:
    ax.set_xlim(0, shape[1])
    ax.set_ylim(shape[0], 0)
    ax.set_aspect("equal")
    ax.set_xlabel("column (px)")
    ax.set_ylabel("row (px)")


def needle_panel(rows, cols, alpha, flow, *, shape, title: str, scale_px: float | None = None) -> Figure:
    """Normal flow as needles along ``(cos alpha, sin alpha)`` at each point.

    ``flow`` in px per unit time; needles are scaled so the longest is about
    6 px unless ``scale_px`` (drawn length per unit flow) is given: give the
    same one (:func:`needle_scale_px`) to panels that are to be compared.
    """
    flow = np.asarray(flow, dtype=float)
    ok = np.isfinite(flow)
    fig = _figure()
    ax = fig.add_subplot()
    if scale_px is None:
        scale_px = needle_scale_px(flow)
    dc = np.cos(alpha[ok]) * flow[ok] * scale_px
    dr = np.sin(alpha[ok]) * flow[ok] * scale_px
    ax.quiver(cols[ok], rows[ok], dc, dr, angles="xy", scale_units="xy", scale=1.0, width=0.003, headwidth=0, headlength=0, headaxislength=0, color="k")
    _image_axes(ax, shape)
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
    _image_axes(ax, shape)
    ax.set_title(title)
    ax.legend(loc="lower right", fontsize=6, markerscale=4)
    return fig


def yz_projection_panel(points, *, true_points=None, title: str, unit: str = "scene units") -> Figure:
    """Recovered 3-D points projected on the Y-Z plane (red), with the truth drawn over them (small black dots)."""
    fig = _figure(5.0, 4.0)
    ax = fig.add_subplot()
    pts = np.asarray(points, dtype=float)
    ok = np.all(np.isfinite(pts), axis=1)
    ax.scatter(pts[ok, 2], pts[ok, 1], s=6, c="tab:red", linewidths=0, label="recovered")
    if true_points is not None:  # on top: where the two agree, both show
        tp = np.asarray(true_points, dtype=float)
        tok = np.all(np.isfinite(tp), axis=1)
        ax.scatter(tp[tok, 2], tp[tok, 1], s=0.8, c="k", linewidths=0, label="true")
    ax.invert_yaxis()
    ax.set_xlabel(f"Z, depth ({unit})")
    ax.set_ylabel(f"Y, down ({unit})")
    ax.set_title(title)
    ax.legend(fontsize=7, markerscale=3)
    return fig


def colormap_panel(array, *, title: str, unit: str, cmap: str = "turbo", vmin=None, vmax=None) -> Figure:
    """A colour map with a colour bar in ``unit`` (NaN drawn black; an all-NaN map says so, with no colour bar).

    ``vmin``/``vmax`` default to the finite values' 1st and 99th
    percentiles; values beyond the range are drawn at its ends and the
    colour bar says so with an arrow at that end. ``cmap`` is a matplotlib
    colour-map name or a Colormap object.
    """
    for name, v in (("vmin", vmin), ("vmax", vmax)):
        if v is not None and not np.isfinite(v):
            msg = f"{name} must be a finite number, got {v!r}"
            raise ValueError(msg)
    if vmin is not None and vmax is not None and vmax < vmin:
        msg = f"vmax must be >= vmin, got vmin={vmin!r}, vmax={vmax!r}"
        raise ValueError(msg)
    arr = np.asarray(array, dtype=float)
    fig = _figure(5.5, 4.0)
    ax = fig.add_subplot()
    base = matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap
    colours = base.with_extremes(bad="black")
    finite = arr[np.isfinite(arr)]
    lo = float(np.percentile(finite, 1)) if finite.size else 0.0
    hi = float(np.percentile(finite, 99)) if finite.size else 1.0
    # one end given: the other follows the data, never crossing it
    lo, hi = (lo if vmin is None else float(vmin)), (hi if vmax is None else float(vmax))
    if vmin is None:
        lo = min(lo, hi)
    if vmax is None:
        hi = max(hi, lo)
    im = ax.imshow(np.ma.masked_invalid(arr), cmap=colours, vmin=lo, vmax=hi, interpolation="nearest")
    ax.set_title(title)
    ax.set_axis_off()
    if not finite.size:  # no value: no scale to read (a 0..1 bar would suggest one)
        ax.text(0.5, 0.5, "no finite value", transform=ax.transAxes, ha="center", va="center", color="white")
        return fig
    below, above = bool(finite.min() < lo), bool(finite.max() > hi)
    extend = "both" if below and above else "min" if below else "max" if above else "neither"
    fig.colorbar(im, ax=ax, label=unit, shrink=0.85, extend=extend)
    return fig
