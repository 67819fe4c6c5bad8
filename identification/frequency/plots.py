"""Bode plots of frequency responses, with coherence; points of low coherence drawn faint
(Tischler & Remple 2012).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from flightid.identification.frequency.response import FrequencyResponse

COHERENCE_PLOT_MIN = 0.6  # below it a response point is drawn faint (Tischler & Remple)


def bode_figure(responses: Sequence[FrequencyResponse], title: str = "") -> Figure:
    """Matplotlib figure: magnitude (dB), phase (deg) and coherence against frequency (Hz).

    Points with coherence below 0.6 are drawn faint.

    Parameters
    ----------
    responses : sequence of FrequencyResponse
        The responses drawn, one line each.
    title : str, optional
        The figure title. Default none.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    fig = Figure(figsize=(7.5, 8))
    axes = fig.subplots(3, 1, sharex=True,
                        gridspec_kw={"height_ratios": [2, 2, 1]})
    for r in responses:
        label = f"{r.output}/{r.input}"
        ok = np.isfinite(r.response)
        f, mag = r.frequency[ok], r.magnitude_db[ok]
        phase = np.degrees(np.unwrap(np.angle(r.response[ok])))
        # the whole curve faint, the points with coherence >= 0.6 (usable, CIFER) solid
        good = np.where(r.coherence[ok] >= COHERENCE_PLOT_MIN, 1.0, np.nan)
        (line,) = axes[0].semilogx(f, mag, alpha=0.25)
        axes[0].semilogx(f, mag * good, color=line.get_color(), label=label)
        axes[1].semilogx(f, phase, color=line.get_color(), alpha=0.25)
        axes[1].semilogx(f, phase * good, color=line.get_color())
        axes[2].semilogx(r.frequency, r.coherence, color=line.get_color())
    axes[0].set_ylabel("magnitude (dB)")
    axes[1].set_ylabel("phase (deg)")
    axes[2].set_ylabel("coherence")
    axes[2].axhline(0.6, color="0.5", ls="--", lw=0.8)
    axes[2].set_ylim(0, 1.05)
    axes[2].set_xlabel("frequency (Hz)")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend()
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    return fig


def bode_overlay_figure(measured: Sequence[FrequencyResponse], model: Sequence[np.ndarray],
                        coherence_min: float = 0.6, title: str = ""):
    """Matplotlib figure: measured responses with the identified model's responses overlaid.

    Magnitude (dB), phase (deg), coherence against frequency (Hz); measured points where
    coherence >= ``coherence_min``, model as lines.

    Parameters
    ----------
    measured : sequence of FrequencyResponse
        The measured responses.
    model : sequence of numpy.ndarray
        The model's complex responses on the same frequencies, one per measured response.
    coherence_min : float, optional
        The smallest coherence of a drawn measured point. Default 0.6.
    title : str, optional
        The figure title. Default none.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.

    Raises
    ------
    ValueError
        When ``measured`` and ``model`` differ in length.
    """
    if len(measured) != len(model):
        raise ValueError(f"{len(measured)} measured responses but {len(model)} model ones")
    fig = Figure(figsize=(8, 9))
    axes = fig.subplots(3, 1, sharex=True,
                        gridspec_kw={"height_ratios": [2, 2, 1]})
    for k, (r, h) in enumerate(zip(measured, model, strict=True)):
        colour = f"C{k % 10}"
        ok = r.valid(coherence_min)
        h = np.asarray(h, dtype=complex)
        phase_model = np.degrees(np.unwrap(np.angle(h)))
        phase_meas = np.degrees(np.angle(r.response))
        # measured phase put on the model's branch, so the two overlay
        phase_meas = phase_model + ((phase_meas - phase_model + 180.0) % 360.0 - 180.0)
        axes[0].semilogx(r.frequency[ok], r.magnitude_db[ok], "o", ms=3, color=colour,
                         label=f"{r.output}/{r.input}")
        axes[0].semilogx(r.frequency, 20 * np.log10(np.abs(h)), "-", color=colour)
        axes[1].semilogx(r.frequency[ok], phase_meas[ok], "o", ms=3, color=colour)
        axes[1].semilogx(r.frequency, phase_model, "-", color=colour)
        axes[2].semilogx(r.frequency, r.coherence, "-", color=colour)
    axes[0].set_ylabel("magnitude (dB)")
    axes[1].set_ylabel("phase (deg)")
    axes[2].set_ylabel("coherence")
    axes[2].axhline(coherence_min, color="0.5", ls="--", lw=0.8)
    axes[2].set_ylim(0, 1.05)
    axes[2].set_xlabel("frequency (Hz)")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2, title="points: measured, lines: model",
                   title_fontsize=7)
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    return fig
