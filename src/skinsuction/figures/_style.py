"""Shared look of the figures: sizes, fonts, colours per boundary condition."""

from __future__ import annotations

import contextlib

import matplotlib

matplotlib.use("Agg")  # files only, no screen

import matplotlib.pyplot as plt  # noqa: E402

from skinsuction._files import atomic_output

#: Figure width of a two-column journal figure (inches).
WIDTH_IN = 7.0

#: Plot style of the three hypodermis/bone interface conditions (paper section 3.1).
BOTTOM_STYLE = {
    "fixed": {
        "color": "#1b6ca8",
        "marker": "o",
        "linestyle": "-",
        "label": "restrained laterally and axially (fixed)",
    },
    "axial": {
        "color": "#d1495b",
        "marker": "s",
        "linestyle": "--",
        "label": "restrained axially (axial)",
    },
    "free": {
        "color": "#2e933c",
        "marker": "^",
        "linestyle": ":",
        "label": "interface suppressed (free)",
    },
}

#: The study's Matplotlib settings (:func:`style`).
RC = {
    "font.size": 9,
    "axes.labelsize": 9,
    "axes.titlesize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "lines.linewidth": 1.2,
    "lines.markersize": 5,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "savefig.dpi": 300,
    "pdf.fonttype": 42,  # embed TrueType: editable text in the PDF
    "svg.hashsalt": "skinsuction",
}


@contextlib.contextmanager
def style():
    """Context in which the study's Matplotlib settings (:data:`RC`) apply.

    Public as :func:`skinsuction.figures.figure_style`.

    Yields
    ------
    None
    """
    with plt.rc_context(RC):
        yield


def panel_label(ax, text):
    """Write a panel label such as ``(a)`` in the upper left corner of ``ax``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The panel.
    text : str
        The label.

    Returns
    -------
    None
    """
    ax.text(
        0.02, 0.98, text, transform=ax.transAxes, ha="left", va="top", fontweight="bold"
    )


def save(fig, *paths):
    """Save ``fig`` to each path (format from the suffix) atomically and reproducibly.

    Public as :func:`skinsuction.figures.save_figure`.  Time stamps are left out of
    the files so that the same data give the same bytes.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    *paths : path-like
        The files (``.png``, ``.pdf``, ``.svg`` ...); each is written through a
        temporary file and moved into place.

    Returns
    -------
    None
    """
    for path in paths:
        path = str(path)
        fmt = path.rsplit(".", 1)[-1].lower()
        meta = {"pdf": {"CreationDate": None, "ModDate": None}, "png": {"Software": None}}
        with atomic_output(path) as tmp:
            fig.savefig(tmp, format=fmt, metadata=meta.get(fmt), bbox_inches="tight")
