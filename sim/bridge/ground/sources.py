"""MAVLink sources and the packets lost between those received from each.

Lost packets are counted from MAVLink sequence numbers per (sysid, compid). A sequence
number has 8 bits, so a gap of more than 255 packets wraps; gaps are unwrapped with the
source's own time stamps and its mean packet rate (the wrap count closest to rate * dt).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

Source = tuple[int, int]


def source_name(src: Source) -> str:
    """'sysid/compid' of a source.

    Parameters
    ----------
    src : tuple of (int, int)
        (system id, component id).

    Returns
    -------
    str
        'sysid/compid'.
    """
    return f"{src[0]}/{src[1]}"


@dataclass
class SourceLoss:
    """Packets received from one source and packets missing between them."""

    received: int = 0
    lost: int = 0
    wraps: int = 0  # gaps longer than 255 packets found by the time stamps

    @property
    def loss_rate(self) -> float:
        """lost / (received + lost)."""
        total = self.received + self.lost
        return self.lost / total if total else 0.0


def sequence_losses(packets: list[tuple[Source, int, float | None]]) -> dict[Source, SourceLoss]:
    """Per source, packets lost between the first and last received (seq gaps).

    Between two received packets that carry time stamps, the number of 256-packet wraps is
    the one that brings the sequence advance closest to (mean packet rate) * (time between
    them).

    Parameters
    ----------
    packets : list of tuple
        (source, seq, message time in s or None) in arrival order.

    Returns
    -------
    dict of Source to SourceLoss
        Packets received, lost and wraps found, by source.
    """
    by_src: dict[Source, list[tuple[int, float]]] = {}
    for src, seq, t in packets:
        by_src.setdefault(src, []).append((seq, np.nan if t is None else t))
    out = {}
    for src, items in by_src.items():
        seq = np.array([s for s, _ in items])
        t = np.array([x for _, x in items], dtype=float)
        adv = (np.diff(seq) % 256).astype(float)
        adv[adv == 0] = 256.0  # same seq again: a full wrap (as mavutil counts it)
        timed = np.flatnonzero(np.isfinite(t))
        wraps = 0
        if len(timed) >= 2:
            # advance and elapsed time between consecutive time-stamped packets
            seg_adv = np.array([adv[a:b].sum() for a, b in zip(timed[:-1], timed[1:],
                                                                strict=True)])
            seg_dt = np.diff(t[timed])
            for _ in range(2):  # the rate from the unwrapped advances, then once more
                pos = seg_dt > 0
                if not pos.any() or seg_dt[pos].sum() <= 0:
                    break
                rate = seg_adv.sum() / seg_dt[pos].sum()
                k = np.where(pos, np.round((rate * seg_dt - seg_adv) / 256.0), 0.0)
                k = np.maximum(k, 0.0)
                seg_adv = seg_adv + 256.0 * k
                wraps += int(k.sum())
            total = seg_adv.sum() + adv[: timed[0]].sum() + adv[timed[-1]:].sum()
        else:
            total = adv.sum()
        out[src] = SourceLoss(len(items), int(total - (len(items) - 1)), wraps)
    return out


def loss_dict(losses: dict[Source, SourceLoss]) -> dict[str, dict]:
    """Per source name: packets received and lost, the loss rate and the wraps.

    Parameters
    ----------
    losses : dict of Source to SourceLoss
        Losses by source.

    Returns
    -------
    dict of str to dict
        By 'sysid/compid': received, lost, loss_rate (fraction), wraps.
    """
    return {source_name(s): {"received": v.received, "lost": v.lost, "loss_rate": v.loss_rate,
                             "wraps": v.wraps} for s, v in sorted(losses.items())}
