"""Read NASA SIDPAC flight-data files (MATLAB .mat with ``fdata``/``t``) into a FlightRecord.

SIDPAC (Morelli & Klein 2016, appendix B) stores one maneuver as ``fdata``, an N x 90
matrix with a fixed column layout (ft, slug, deg, g, psf), the time vector ``t`` (s), the
reference geometry ``sarea`` (ft^2), ``bspan`` and ``cbar`` (ft), and a description
struct ``fds``. Everything is converted to SI and the canonical channel names of
``flightid.channels`` here, once.

Choices made for the Twin Otter record (totter_f1_017, checked against its own
coefficient columns):

* ``ax ay az`` are fdata columns 11-13 (the specific forces at the CG that SIDPAC
  computed the CX and CZ columns from: they reproduce CX and CZ to 1e-16). The raw
  accelerometer readings, columns 53-55, are kept as ``ax_meas ay_meas az_meas`` (m/s^2).
* ``thrust`` is the sum of columns 38 and 39 (one per engine; column 39 is unlabelled in
  the file). Their sum over qbar*S reproduces the CT column; each engine is kept as
  ``thrust_1`` and ``thrust_2`` (N).
* ``da`` (``ail``) and ``dr`` (``rdr``) keep their SIDPAC sign: positive aileron gives a
  negative rolling moment and positive rudder a negative yawing moment (published
  Cl_da = -0.21, Cn_dr = -0.13), which is the project convention.
* The file's own CY, phat and rhat columns are kept as they are. They were computed by
  SIDPAC after data compatibility: CY = m (ay + 0.1134 g) / (qbar S) (a constant lateral
  accelerometer bias removed), phat = (p - 0.00194 rad/s) b / 2V and rhat = (r + 0.0193
  rad/s) b / 2V (rate biases removed). With a bias term in the regression these constant
  corrections leave the derivative estimates unchanged to < 1 %.
* ``time`` is ``t`` (starting at 0); the clock time of the first sample (fdata column 1,
  s of day) is kept in ``meta.extra['clock_time_start']``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import scipy.io

from flightid.flight_record import FlightRecord, RecordMeta, Reference, check_samples
from flightid.units import DEG, FT, G0, IN, LBF, PSF, SLUG, SLUG_FT2, SLUG_FT3

# (1-based fdata column, flightid channel name, factor to SI)
COLUMNS: tuple[tuple[int, str, float], ...] = (
    (2, "V", FT),
    (3, "beta", DEG),
    (4, "alpha", DEG),
    (5, "p", DEG),
    (6, "q", DEG),
    (7, "r", DEG),
    (8, "phi", DEG),
    (9, "theta", DEG),
    (10, "psi", DEG),
    (11, "ax", G0),
    (12, "ay", G0),
    (13, "az", G0),
    (14, "de", DEG),
    (15, "da", DEG),
    (16, "dr", DEG),
    (27, "qbar", PSF),
    (29, "rho", SLUG_FT3),
    (30, "h", FT),
    (38, "thrust_1", LBF),
    (39, "thrust_2", LBF),
    (42, "pdot", DEG),
    (43, "qdot", DEG),
    (44, "rdot", DEG),
    (45, "xcg", IN),
    (46, "ycg", IN),
    (47, "zcg", IN),
    (48, "mass", SLUG),
    (49, "Ixx", SLUG_FT2),
    (50, "Iyy", SLUG_FT2),
    (51, "Izz", SLUG_FT2),
    (52, "Ixz", SLUG_FT2),
    (53, "ax_meas", G0),
    (54, "ay_meas", G0),
    (55, "az_meas", G0),
    (61, "CX", 1.0),
    (62, "CY", 1.0),
    (63, "CZ", 1.0),
    (64, "Cl", 1.0),
    (65, "Cm", 1.0),
    (66, "Cn", 1.0),
    (67, "CD", 1.0),
    (68, "CYw", 1.0),
    (69, "CL", 1.0),
    (70, "CT", 1.0),
    (71, "phat", 1.0),
    (72, "qhat", 1.0),
    (73, "rhat", 1.0),
    (74, "u", FT),
    (75, "v", FT),
    (76, "w", FT),
)

# channels that are not in flightid.channels: their SI unit and meaning
EXTRA_UNITS: dict[str, str] = {
    "ax_meas": "m/s^2",
    "ay_meas": "m/s^2",
    "az_meas": "m/s^2",
    "thrust_1": "N",
    "thrust_2": "N",
    "xcg": "m",
    "ycg": "m",
    "zcg": "m",
    "CYw": "-",
    "CT": "-",
}
EXTRA_DESCRIPTIONS: dict[str, str] = {
    "ax_meas": "accelerometer x reading at the sensor (SIDPAC fdata col 53 axm)",
    "ay_meas": "accelerometer y reading at the sensor (SIDPAC fdata col 54 aym)",
    "az_meas": "accelerometer z reading at the sensor (SIDPAC fdata col 55 azm)",
    "thrust_1": "thrust of engine 1 (SIDPAC fdata col 38)",
    "thrust_2": "thrust of engine 2 (SIDPAC fdata col 39, unlabelled in the file)",
    "xcg": "CG x position in the aircraft's station frame (SIDPAC col 45)",
    "ycg": "CG y position in the aircraft's station frame (SIDPAC col 46)",
    "zcg": "CG z position in the aircraft's station frame (SIDPAC col 47)",
    "CYw": "side force coefficient, wind axes (SIDPAC col 68)",
    "CT": "thrust coefficient T / (qbar S) (SIDPAC col 70)",
}

N_COLUMNS = 90
AIRCRAFT_NAMES = {"twin otter": "NASA Twin Otter (DHC-6)"}


def read_mat(path: str | Path) -> FlightRecord:
    """Read a SIDPAC .mat flight-data file into a FlightRecord in SI units (m, s, rad, N, kg).

    Parameters
    ----------
    path : str or pathlib.Path
        The .mat file with ``fdata`` and ``t`` (and optionally ``fds``).

    Returns
    -------
    FlightRecord
        The flight, SI channels.

    Raises
    ------
    FileNotFoundError
        When the file is missing.
    ValueError
        Naming the file when it is not a readable SIDPAC flight-data file.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    try:
        mat = scipy.io.loadmat(path, squeeze_me=False)
    except Exception as exc:  # scipy raises several types for a bad file
        raise ValueError(f"{path}: not a readable MATLAB .mat file ({exc})") from exc
    for key in ("fdata", "t"):
        if key not in mat:
            present = ", ".join(k for k in mat if not k.startswith("__")) or "none"
            raise ValueError(
                f"{path}: not a SIDPAC flight-data file: variable {key!r} is missing "
                f"(variables present: {present})"
            )
    try:
        fdata = np.asarray(mat["fdata"], dtype=float)
        time = np.asarray(mat["t"], dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"{path}: fdata and t must be numeric arrays (got "
                         f"{type(mat['fdata']).__name__} of {getattr(mat['fdata'], 'dtype', '?')}"
                         f", {getattr(mat['t'], 'dtype', '?')})") from None
    if fdata.ndim != 2 or fdata.shape[1] < N_COLUMNS:
        raise ValueError(
            f"{path}: fdata has shape {fdata.shape}; SIDPAC fdata has {N_COLUMNS} columns"
        )
    if fdata.shape[0] != time.size:
        raise ValueError(f"{path}: fdata has {fdata.shape[0]} rows but t has {time.size} samples")

    channels: dict[str, np.ndarray] = {}
    for col, name, factor in COLUMNS:
        channels[name] = fdata[:, col - 1] * factor
    check_samples(f"{path} (SIDPAC fdata)", time, channels)
    channels["thrust"] = channels["thrust_1"] + channels["thrust_2"]

    fds = _struct(mat.get("fds"))
    try:
        area = _scalar(mat, fds, "sarea", fdata[:, 76])
        span = _scalar(mat, fds, "bspan", fdata[:, 77])
        chord = _scalar(mat, fds, "cbar", fdata[:, 78])
    except (ValueError, TypeError, IndexError) as exc:
        raise ValueError(f"{path}: {exc}") from None
    aircraft_raw = _text(fds.get("aircraft")) or "unknown"
    aircraft = AIRCRAFT_NAMES.get(aircraft_raw.strip().lower(), aircraft_raw)
    dt = float(np.mean(np.diff(time))) if time.size > 1 else 0.0

    # the reference condition of a perturbation model is the record mean, as in SIDPAC
    condition: dict[str, Any] = {
        k: float(np.mean(channels[k])) for k in ("V", "h", "alpha", "beta", "qbar", "rho", "mass")
    }
    condition["note"] = "means over the record (SI units), the reference of perturbation models"
    extra: dict[str, Any] = {
        "source_format": "SIDPAC fdata",
        "clock_time_start": float(fdata[0, 0]),
        "maneuver": _text(fds.get("maneuver")),
        "description": _text(fds.get("description")),
        "test_date": _text(fds.get("test_date")),
        "created": _text(fds.get("created")),
        "accelerations": "ax ay az = fdata cols 11-13 (at the CG, used for CX..CZ); "
        "ax_meas ay_meas az_meas = cols 53-55 (accelerometer readings)",
        "channel_descriptions": dict(EXTRA_DESCRIPTIONS),
    }
    meta = RecordMeta(
        aircraft=aircraft,
        condition=condition,
        sample_rate=1.0 / dt if dt > 0 else 0.0,
        provenance=f"SIDPAC flight data file {path.name}",
        reference=Reference(area=area * FT**2, span=span * FT, chord=chord * FT),
        units=dict(EXTRA_UNITS),
        extra=extra,
    )
    return FlightRecord(time, channels, meta)


def _struct(value: Any) -> dict[str, Any]:
    """A MATLAB 1x1 struct loaded by scipy as a dict of its fields ({} if absent)."""
    if value is None or not hasattr(value, "dtype") or value.dtype.names is None:
        return {}
    item = value.ravel()[0]
    return {name: item[name] for name in value.dtype.names}


def _text(value: Any) -> str:
    """A MATLAB char array or number as a plain string ('' if empty)."""
    if value is None:
        return ""
    arr = np.asarray(value)
    if arr.size == 0:
        return ""
    if arr.dtype.kind in "US":
        return " ".join(str(s).strip() for s in arr.ravel())
    if arr.dtype == object:
        return " ".join(_text(v) for v in arr.ravel())
    return " ".join(str(v.item() if hasattr(v, "item") else v) for v in arr.ravel())


def _scalar(mat: dict[str, Any], fds: dict[str, Any], key: str, column: np.ndarray) -> float:
    """A reference-geometry value (ft units) from the file variable, fds, or its fdata column."""
    for source in (mat.get(key), fds.get(key)):
        if source is not None and np.asarray(source).size == 1:
            return float(np.asarray(source, dtype=float).ravel()[0])
    if np.any(column != 0):
        return float(np.mean(column))
    raise ValueError(f"reference geometry {key!r} is missing (no variable and fdata column is 0)")
