"""The picture of an episode (``render_mode="rgb_array"``): actions, rates and angles."""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from flightid.scenarios.gym.options import CONTROLS, OBS_CHANNELS


def render_episode(obs: np.ndarray, act: np.ndarray, aircraft: str, logdet: float
                   ) -> np.ndarray:
    """An RGB image (height x width x 3, uint8) of an episode: the actions (-1..1), the
    rates p, q, r (deg/s) and the angles alpha, beta, phi (deg) against time (s), from the
    observations ``obs`` (rows of ``OBS_CHANNELS``) and actions ``act`` (rows of de, da,
    dr), titled with the aircraft and the log det of the information gathered.

    Parameters
    ----------
    obs : numpy.ndarray
        Observations, rows of ``OBS_CHANNELS`` (time first, s); shape (n, len(OBS_CHANNELS)).
    act : numpy.ndarray
        Normalised actions (de, da, dr); shape (n, 3).
    aircraft : str
        Aircraft name for the title.
    logdet : float
        Log det of the targets' information, for the title.

    Returns
    -------
    numpy.ndarray
        RGB image, uint8; shape (height, width, 3).
    """
    fig = Figure(figsize=(6.4, 4.8), dpi=80)
    canvas = FigureCanvasAgg(fig)
    ax1, ax2, ax3 = fig.subplots(3, 1, sharex=True)
    t = obs[:, 0]
    for i, c in enumerate(CONTROLS):
        ax1.plot(t, act[:, i], label=c)
    ax1.set_ylabel("action")
    ax1.set_ylim(-1.05, 1.05)
    ax1.legend(loc="upper right", fontsize=7)
    for c in ("p", "q", "r"):
        ax2.plot(t, np.degrees(obs[:, OBS_CHANNELS.index(c)]), label=c)
    ax2.set_ylabel("rate (deg/s)")
    ax2.legend(loc="upper right", fontsize=7)
    for c in ("alpha", "beta", "phi"):
        ax3.plot(t, np.degrees(obs[:, OBS_CHANNELS.index(c)]), label=c)
    ax3.set_ylabel("angle (deg)")
    ax3.set_xlabel("t (s)")
    ax3.legend(loc="upper right", fontsize=7)
    fig.suptitle(f"{aircraft}: log det information {logdet:.1f}", fontsize=9)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()
