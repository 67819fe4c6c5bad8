"""Where the gap lies: the residual of each output by frequency band, by window and by
flight regime.

The model as is (only its nuisance parameters fitted) is simulated with each window's
measured inputs; each output's residual is split into frequency bands by its discrete
Fourier transform (Parseval), and each band's energy is given as a fraction of the
measured signal's energy (mean removed) on that window. A fraction near 0: the model
reproduces the channel; near 1 or above: the model misses it. By regime: the samples of
all windows pooled and split into ``REGIME_BINS`` equal-count bins of the measured angle
of attack and of the airspeed; each bin's residual energy over the measured energy (each
window's mean removed) of its samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from matplotlib.figure import Figure

from flightid.identification.gap.fit import WindowFit
from flightid.record import FlightRecord

BANDS: tuple[tuple[float, float], ...] = ((0.0, 0.3), (0.3, 1.0), (1.0, 3.0), (3.0, math.inf))
REGIME_BINS = 3  # equal-count bins of each regime variable
REGIMES = {"alpha": ("deg", 180.0 / math.pi), "V": ("m/s", 1.0)}  # variable: unit, scale


def band_label(band: tuple[float, float]) -> str:
    """A band's label for tables ("<0.3 Hz", "1-3 Hz", ">3 Hz").

    Parameters
    ----------
    band : tuple of float
        (low, high), Hz; low 0 or high inf for the open ends.

    Returns
    -------
    str
    """
    lo, hi = band
    return f"<{hi:g} Hz" if lo == 0 else (f">{lo:g} Hz" if math.isinf(hi) else f"{lo:g}-{hi:g} Hz")


def band_fractions(residual: np.ndarray, measured: np.ndarray, dt: float,
                   bands: tuple[tuple[float, float], ...] = BANDS) -> list[float]:
    """Residual energy in each band / measured energy (mean removed), by Parseval.

    Parameters
    ----------
    residual, measured : ndarray
        One output's residual and measured signal on one window.
    dt : float
        Sample interval, s.
    bands : tuple of (float, float)
        Frequency bands, Hz.

    Returns
    -------
    list of float
        Per band, the residual energy over the measured energy (nan for a constant signal).
    """
    n = residual.size
    f = np.fft.rfftfreq(n, dt)
    weight = np.full(f.size, 2.0)
    weight[0] = 1.0
    if n % 2 == 0:
        weight[-1] = 1.0
    er = weight * np.abs(np.fft.rfft(residual)) ** 2
    total = float(np.sum(weight * np.abs(np.fft.rfft(measured - np.mean(measured))) ** 2))
    if total <= 0:
        return [float("nan")] * len(bands)
    return [float(np.sum(er[(f >= lo) & (f < hi)]) / total) for lo, hi in bands]


@dataclass
class GapMap:
    """Rows per (window, channel): total residual fraction and its split by band."""

    bands: tuple[tuple[float, float], ...]
    rows: list[dict] = field(default_factory=list)
    # by regime: {"variable", "unit", "low", "high", "channel", "fraction", "samples"}
    regimes: list[dict] = field(default_factory=list)

    def channels(self) -> list[str]:
        return list(dict.fromkeys(r["channel"] for r in self.rows))

    def windows(self) -> list[str]:
        return list(dict.fromkeys(r["window"] for r in self.rows))

    def by_channel(self) -> dict[str, dict[str, float]]:
        """Per channel, band fractions averaged over the windows, and the total."""
        out: dict[str, dict[str, float]] = {}
        for ch in self.channels():
            rows = [r for r in self.rows if r["channel"] == ch]
            d = {b: float(np.nanmean([r["bands"][b] for r in rows])) for b in rows[0]["bands"]}
            d["total"] = float(np.nanmean([r["total"] for r in rows]))
            out[ch] = d
        return out

    def to_json(self) -> dict:
        return {"bands": [band_label(b) for b in self.bands], "rows": self.rows,
                "by_channel": self.by_channel(), "regimes": self.regimes}


def regime_rows(fits: dict[str, WindowFit], records: dict[str, FlightRecord],
                bins: int = REGIME_BINS) -> list[dict]:
    """Per regime variable (alpha, V: measured, from each window's record) and bin, each
    output's residual energy / measured energy (window means removed) over the samples in
    the bin; a variable the records lack is left out.

    Parameters
    ----------
    fits : dict of str to WindowFit
        The model-as-is fits by window label.
    records : dict of str to FlightRecord
        The windows' records, same labels.
    bins : int
        Equal-count bins per regime variable.

    Returns
    -------
    list of dict
        Per variable (alpha deg, V m/s), bin and channel: "variable", "unit", "low",
        "high", "channel", "fraction" and "samples".
    """
    out: list[dict] = []
    labels = [k for k in fits if k in records]
    for var, (unit, scale) in REGIMES.items():
        if not labels or not all(var in records[k] for k in labels):
            continue
        x = np.concatenate([np.interp(fits[k].time, records[k].time, records[k][var]) * scale
                            for k in labels])
        edges = np.quantile(x, np.linspace(0.0, 1.0, bins + 1))
        which = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, bins - 1)
        for ch in fits[labels[0]].residual:
            res = np.concatenate([fits[k].residual[ch] for k in labels])
            meas = np.concatenate([fits[k].measured[ch] - np.mean(fits[k].measured[ch])
                                   for k in labels])
            for b in range(bins):
                sel = which == b
                spread = float(np.sum(meas[sel] ** 2))
                out.append({"variable": var, "unit": unit, "low": float(edges[b]),
                            "high": float(edges[b + 1]), "channel": ch,
                            "fraction": float(np.sum(res[sel] ** 2)) / spread
                            if spread > 0 else float("nan"), "samples": int(np.sum(sel))})
    return out


def gap_map(fits: dict[str, WindowFit], bands: tuple[tuple[float, float], ...] = BANDS,
            records: dict[str, FlightRecord] | None = None) -> GapMap:
    """The gap map of the model-as-is fits of each window (``{window label: fit}``); by
    regime too when the windows' ``records`` are given.

    Parameters
    ----------
    fits : dict of str to WindowFit
        The model-as-is fits by window label.
    bands : tuple of (float, float)
        Frequency bands, Hz.
    records : dict of str to FlightRecord or None
        The windows' records (for the regime rows).

    Returns
    -------
    GapMap
        Per window and channel the residual fraction and its split by band; by regime when
        ``records`` are given.
    """
    out = GapMap(bands, regimes=regime_rows(fits, records) if records else [])
    labels = [band_label(b) for b in bands]
    for window, wf in fits.items():
        dt = float(np.median(np.diff(wf.time)))
        for ch, res in wf.residual.items():
            fr = band_fractions(res, wf.measured[ch], dt, bands)
            out.rows.append({"window": window, "channel": ch,
                             "total": float(wf.fractions()[ch]),
                             "bands": dict(zip(labels, fr, strict=True))})
    return out


def heat_map(gm: GapMap, title: str = "") -> Figure:
    """Channels x bands (averaged over windows) and channels x windows (total).

    Parameters
    ----------
    gm : GapMap
        The gap map.
    title : str
        The figure's title.

    Returns
    -------
    Figure
    """
    chans = gm.channels()
    labels = [band_label(b) for b in gm.bands]
    per = gm.by_channel()
    a = np.array([[per[c][b] for b in labels] for c in chans])
    wins = gm.windows()
    w = np.array([[next((r["total"] for r in gm.rows if r["channel"] == c and r["window"] == k),
                        math.nan) for k in wins] for c in chans])
    fig = Figure(figsize=(4.0 + 1.1 * (len(labels) + len(wins)), 0.5 * len(chans) + 2.6),
                 layout="constrained")
    axes = fig.subplots(1, 2, gridspec_kw={"width_ratios": [len(labels), max(len(wins), 1)]})
    vmax = max(1.0, float(np.nanmax(np.concatenate([a.ravel(), w.ravel()]))))
    for ax, data, cols, name in ((axes[0], a, labels, "by band (mean over windows)"),
                                 (axes[1], w, wins, "by window (all bands)")):
        im = ax.imshow(data, cmap="magma_r", vmin=0.0, vmax=vmax, aspect="auto")
        ax.set_xticks(range(len(cols)), cols, rotation=30, ha="right", fontsize=8)
        ax.set_yticks(range(len(chans)), chans)
        ax.set_title(name, fontsize=9)
        for i in range(data.shape[0]):
            for j in range(data.shape[1]):
                v = data[i, j]
                if not math.isfinite(v):
                    continue
                ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=8,
                        color="white" if v > 0.5 * vmax else "black")
    fig.colorbar(im, ax=list(axes), label="residual energy / measured energy", shrink=0.8)
    fig.suptitle(title or "gap map: the model as is", fontsize=10)
    return fig
