"""The standard data reduction before identification: accelerometers and flow vanes
corrected to the CG from the sensor positions a record carries, and the vanes' flow
amplification (upwash, sidewash) and bias from flight path reconstruction.

As the F-111C reduction procedure (Cooper, Drobik & Martin, ARL Flight Mechanics Report
187, 1990, sections 4.3-4.4) and Morelli & Klein (2016) ch. 10 do it:

- accelerometers at r = (x, y, z) m from the CG (body axes) measure
  a_s = a_cg + omegadot x r + omega x (omega x r) (M&K eq. 10.9), so
  a_cg = a_s - omegadot x r - omega x (omega x r), with omegadot from central
  differences of the measured rates (the gyros' bandwidth, as the accelerometers');
- vanes measure alpha_m = K_alpha alpha_v + b_alpha, beta_m = K_beta beta_v + b_beta, with
  alpha_v, beta_v the flow angles at the vane (alpha_v ~ alpha - x_a q / V, beta_v ~ beta
  + x_b r / V; Cooper et al. App. I/J). K and b come from flight path reconstruction
  (``compatibility.reconstruct`` with the vane positions fixed), the position effect is
  then removed exactly (``compatibility.correct``). Without the channels a reconstruction
  needs (phi, theta), only the position effect is removed and the scale is reported left.

The reconstruction assumes steady air (Jategaonkar 2015 ch. 10; Morelli & Klein 2016
ch. 10): wind and turbulence move the vanes but not the kinematics, and the fit then
takes the gusts for vane errors (twinotter-lateral-0alpha in light turbulence: K_alpha
0.0-0.21, beta bias -28 to +40 deg, alpha reduced to 86 rad). A calibration is applied only
when it passes ``calibration_doubts``: residuals at the vanes' noise level (calm air),
K within 0.8-1.2, biases within 5 deg, and Cramer-Rao bounds under 0.02 (K) and 0.5 deg
(bias). Otherwise only the position effect is removed, and a warning says why and which
bias to expect.

The positions are the record's ``meta.extra['sensor_positions']`` (docs/record.md). A record
without them is returned unchanged, with a warning naming the bias to expect.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flightid.identification.compatibility import reconstruction as compatibility
from flightid.identification.compatibility.reconstruction import white_noise_std
from flightid.identification.estimate import Estimate
from flightid.record import FlightRecord

POSITIONS_KEY = "sensor_positions"
SKIPPED = "skipped (--raw)"
REDUCTION_KEY = "data_reduction"
VANE_KEYS = {"alpha": "alpha_vane", "beta": "beta_vane"}
VANE_SCALES = {"alpha": "upwash_alpha", "beta": "sidewash_beta"}
NO_POSITIONS = (
    "the record carries no sensor positions (meta sensor_positions, docs/record.md): "
    "accelerometers and vanes are taken as at the CG. An IMU off the CG biases the "
    "specific forces by omegadot x r + omega x (omega x r) (ay by r_x rdot: CY_r, CY_p, "
    "CY_beta), vanes ahead of the CG read alpha - x q/V and beta + x r/V (Cm_q, CL_q, "
    "CY_r, Cn_r, Cl_r), and an uncalibrated vane scale K scales every flow-angle "
    "derivative by 1/K (CY_beta, Cl_beta, Cn_beta, CL_alpha, Cm_alpha)")
# physical range of a vane calibration: flow amplification K = 1 + k of boom vanes 1.02-1.20
# (Cooper, Drobik & Martin 1990: K_alpha 1.06, K_beta 1.06-1.20), mounting biases of a degree
# or two; and the accuracy a calibration must reach to be worth applying (their Table 1:
# vanes +-0.5 deg; a scale known to 2 % moves the flow-angle derivatives by 2 %)
MAX_VANE_SCALE = 0.2  # |k|: K within 0.8-1.2
MAX_VANE_BIAS = np.radians(5.0)
MAX_VANE_SCALE_STD = 0.02
MAX_VANE_BIAS_STD = np.radians(0.5)
# reconstruction residual over the vane's white noise (``white_noise_std``): 1.1-2.0 in calm
# air on the library cards, 20-58 in light turbulence (twinotter-lateral-0alpha); the noise
# is taken as at least RESIDUAL_FLOOR, the kinematic model's own error (noise-free vanes: beta
# residual 0.024 deg; light turbulence: 0.4-1.2 deg)
MAX_RESIDUAL_RATIO = 5.0
RESIDUAL_FLOOR = np.radians(0.02)
SKIPPED_CALIBRATION = (
    "the flow-angle derivatives (CY_beta, Cl_beta, Cn_beta, CL_alpha, Cm_alpha) then carry "
    "the vanes' flow amplification 1/K: 5 % low in magnitude for K = 1.05, 9 % for 1.10 "
    "(boom vanes: 1.06-1.20, Cooper, Drobik & Martin 1990), and a vane bias moves the "
    "trim flow angle by as much; calibrate the vanes on a calm-air flight and correct the "
    "record, or widen the bounds by that much")


@dataclass
class Reduction:
    """A reduced record, what was applied (one line each) and the warnings."""

    record: FlightRecord
    applied: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    reconstruction: Estimate | None = None


def _position(value: Any, key: str) -> tuple[float, float, float]:
    if (not isinstance(value, list | tuple) or len(value) != 3
            or not all(isinstance(v, int | float) and np.isfinite(v) for v in value)):
        raise ValueError(f"meta sensor_positions.{key} must be [x, y, z] in m, got {value!r}")
    return float(value[0]), float(value[1]), float(value[2])


def accelerometers_to_cg(record: FlightRecord, position: Sequence[float]
                         ) -> dict[str, np.ndarray]:
    """ax, ay, az at the CG from accelerometers at ``position``:
    a_s - omegadot x r - omega x (omega x r) (M&K eq. 10.9).

    omegadot by central differences of the measured rates: the accelerometers saw the
    angular acceleration at the bandwidth of the gyros (same anti-alias filters), and a
    smoothed omegadot (``smoothed_derivative``, 0.2 s) leaves its high-frequency part at
    the input edges in the corrected specific forces: on the twinotter-id card flown by
    ``flightid campaign`` it put CY_beta, CY_p, CY_da, CX_de at 3.5-4.7 sigma (6-DOF
    output error, 19 of 24 within 3 sigma; with central differences 24 of 24).

    Parameters
    ----------
    record : FlightRecord
        The flight, SI channels, with ax, ay, az, p, q, r.
    position : sequence of float
        The accelerometers' (x, y, z), m from the CG, body axes.

    Returns
    -------
    dict of str to numpy.ndarray
        ``ax``, ``ay``, ``az`` at the CG, m/s^2; shape (n,) each.
    """
    x, y, z = position
    t = record.time
    p, q, r = record["p"], record["q"], record["r"]
    pd, qd, rd = (np.gradient(record[c], t) for c in ("p", "q", "r"))
    c1, c2, c3 = q * z - r * y, r * x - p * z, p * y - q * x  # omega x r
    return {"ax": record["ax"] - (qd * z - rd * y) - (q * c3 - r * c2),
            "ay": record["ay"] - (rd * x - pd * z) - (r * c1 - p * c3),
            "az": record["az"] - (pd * y - qd * x) - (p * c2 - q * c1)}


def _with(record: FlightRecord, channels: Mapping[str, np.ndarray],
          positions: Mapping[str, Any], applied: list[str]) -> FlightRecord:
    extra = dict(record.meta.extra)
    extra[POSITIONS_KEY] = dict(positions)
    extra[REDUCTION_KEY] = [*extra.get(REDUCTION_KEY, []), *applied]
    meta = dataclasses.replace(record.meta, extra=extra)
    return FlightRecord(record.time.copy(), {**record.channels, **channels}, meta)


def calibration_doubts(record: FlightRecord, est: Estimate) -> list[str]:
    """Why a flight path reconstruction's vane calibration must not be applied.

    One reason per failed check: alpha or beta residuals above ``MAX_RESIDUAL_RATIO`` times
    the vane's white noise, at least ``RESIDUAL_FLOOR`` (wind or turbulence the kinematics
    cannot see; Jategaonkar 2015 ch. 10), a flow amplification K = 1 + k outside
    1 +- ``MAX_VANE_SCALE``, a bias beyond ``MAX_VANE_BIAS`` (rad), or Cramer-Rao bounds above
    ``MAX_VANE_SCALE_STD`` / ``MAX_VANE_BIAS_STD`` (not identified to the accuracy a
    calibration needs).

    Parameters
    ----------
    record : FlightRecord
        The record the reconstruction was fitted to, SI channels.
    est : Estimate
        The reconstruction's estimate (``compatibility.reconstruct``, Cramer-Rao bounds).

    Returns
    -------
    list of str
        One reason per failed check; empty when the calibration may be applied.
    """
    doubts = []
    residual = est.fit.get("noise_std", {})
    windy = []
    for angle in VANE_KEYS:
        if angle in residual and angle in record:
            noise = max(white_noise_std(record[angle]), RESIDUAL_FLOOR)
            if residual[angle] > MAX_RESIDUAL_RATIO * noise:
                windy.append(f"{angle} {np.degrees(residual[angle]):.2f} deg rms, "
                             f"{residual[angle] / noise:.0f}x the vane's noise "
                             f"({np.degrees(noise):.3f} deg)")
    if windy:
        doubts.append(f"the reconstruction leaves residuals of {', '.join(windy)} (calm air: "
                      f"under 2x): the flow angles carry wind or turbulence that the "
                      f"kinematics cannot see, which the fit takes for vane errors")
    found = dict(zip(est.names, zip(est.values, est.std, strict=True), strict=True))
    for angle, name in VANE_SCALES.items():
        if name in found:
            k, s = found[name]
            if not abs(k) <= MAX_VANE_SCALE:
                doubts.append(f"{angle} vane flow amplification K = {1 + k:.3f} is outside "
                              f"the physical {1 - MAX_VANE_SCALE:g}-{1 + MAX_VANE_SCALE:g}")
            elif not s <= MAX_VANE_SCALE_STD:
                doubts.append(f"{angle} vane flow amplification K = {1 + k:.3f} +- {s:.3f} "
                              f"is not identified (bound > {MAX_VANE_SCALE_STD:g})")
        bias = f"bias_{angle}"
        if bias in found:
            b, s = np.degrees(found[bias])
            if not abs(b) <= np.degrees(MAX_VANE_BIAS):
                doubts.append(f"{angle} vane bias {b:+.2f} deg is beyond the physical "
                              f"+-{np.degrees(MAX_VANE_BIAS):g} deg")
            elif not s <= np.degrees(MAX_VANE_BIAS_STD):
                doubts.append(f"{angle} vane bias {b:+.2f} +- {s:.2f} deg is not identified "
                              f"(bound > {np.degrees(MAX_VANE_BIAS_STD):g} deg)")
    return doubts


def _vanes(record: FlightRecord, vanes: dict[str, tuple[float, float, float]],
           out: Reduction) -> FlightRecord:
    """Vane scale and bias by flight path reconstruction, position effect removed."""
    fixed = {f"vane_{angle}_{axis}": pos[i] for angle, pos in vanes.items()
             for i, axis in enumerate("xyz")}
    values = dict(fixed)
    where = "; ".join(f"{a} vane at ({', '.join(f'{v:g}' for v in pos)}) m"
                      for a, pos in vanes.items())
    missing = [c for c in compatibility.REQUIRED if c not in record]
    if missing:
        out.warnings.append(
            f"vane scale and bias not estimated: flight path reconstruction needs "
            f"{', '.join(missing)}, which the record lacks; the flow-angle derivatives "
            f"(CY_beta, Cl_beta, Cn_beta, CL_alpha, Cm_alpha) carry the vanes' flow "
            f"amplification 1/K")
        out.applied.append(f"flow angles: {where}: position effect removed")
    else:
        _, est = compatibility.reconstruct(record, fixed=fixed, uncertainty="cramer-rao")
        out.reconstruction = est
        doubts = calibration_doubts(record, est)
        if doubts:
            out.warnings.append(
                f"vane scale and bias from flight path reconstruction not applied: "
                f"{'; '.join(doubts)}; {SKIPPED_CALIBRATION}")
            out.applied.append(f"flow angles: {where}: position effect removed; vane scale "
                               f"and bias not applied (implausible or unidentified, see the "
                               f"warning)")
            return compatibility.correct(record, values)
        found = dict(zip(est.names, zip(est.values, est.std, strict=True), strict=True))
        parts = []
        for angle in vanes:
            scale, bias = VANE_SCALES[angle], f"bias_{angle}"
            if scale in found:
                k, s = found[scale]
                values[scale] = float(k)
                parts.append(f"{angle} scale 1 + {k:.4f} +- {s:.4f}")
            elif scale in est.unidentifiable:
                out.warnings.append(f"{angle} vane scale left uncorrected: "
                                    f"{est.unidentifiable[scale]}")
            if bias in found:
                values[bias] = float(found[bias][0])
                parts.append(f"{angle} bias {np.degrees(found[bias][0]):+.3f} deg")
        out.applied.append(f"flow angles: {where}: position effect removed; "
                           f"{', '.join(parts) or 'no scale or bias'} from flight path "
                           f"reconstruction (Morelli & Klein 2016 ch. 10)")
    corrected = compatibility.correct(record, values)
    return corrected


def reduce_record(record: FlightRecord,
                  positions: Mapping[str, Any] | None = None) -> Reduction:
    """The record with the standard data reduction its sensor positions call for.

    Parameters
    ----------
    record : FlightRecord
        A flight record, SI channels.
    positions : mapping, optional
        Sensor positions (m from the CG, body axes) as in ``meta.extra['sensor_positions']``:
        ``accelerometers``, ``alpha_vane``, ``beta_vane``, each [x, y, z]. Default the
        record's own.

    Returns
    -------
    Reduction
        The corrected record (its sensor positions then say the sensors are at the CG, and
        ``meta.extra['data_reduction']`` lists what was done), one line per correction
        applied, and warnings (no positions: the bias to expect).

    Raises
    ------
    ValueError
        For malformed positions.
    """
    if positions is None:
        positions = record.meta.extra.get(POSITIONS_KEY)
    out = Reduction(record)
    if positions is None:
        out.warnings.append(NO_POSITIONS)
        return out
    if not isinstance(positions, Mapping):
        raise ValueError(f"meta sensor_positions must be a table, got {positions!r}")
    left = dict(positions)
    acc = _position(left.get("accelerometers", [0.0, 0.0, 0.0]), "accelerometers")
    channels: dict[str, np.ndarray] = {}
    if any(acc) and all(c in record for c in ("ax", "ay", "az", "p", "q", "r")):
        channels = accelerometers_to_cg(record, acc)
        where = ", ".join(f"{v:g}" for v in acc)
        out.applied.append(f"accelerometers moved to the CG from ({where}) m: "
                           "a - omegadot x r - omega x (omega x r)")
        left["accelerometers"] = [0.0, 0.0, 0.0]
    reduced = _with(record, channels, left, []) if channels else record
    vanes = {angle: _position(left[key], key) for angle, key in VANE_KEYS.items()
             if key in left and angle in record}
    if vanes and all(c in record for c in ("V", "alpha", "beta")):
        reduced = _vanes(reduced, vanes, out)
        for key in VANE_KEYS.values():
            left.pop(key, None)
    if out.applied:
        reduced = _with(reduced, {}, left, out.applied)
    out.record = reduced
    return out


def standard_reduction(record: FlightRecord, raw: bool = False) -> Reduction:
    """What ``flightid identify`` (and each realization of ``flightid montecarlo``) does to a
    record before identifying it.

    ``reduce_record`` with the record's own sensor positions, or, with ``raw`` (``--raw``),
    nothing (``applied`` is [``SKIPPED``]).

    Parameters
    ----------
    record : FlightRecord
        A flight record, SI channels.
    raw : bool, optional
        Skip the reduction. Default False.

    Returns
    -------
    Reduction
        See ``reduce_record``.

    Raises
    ------
    ValueError
        For malformed positions.
    """
    if raw:
        return Reduction(record, applied=[SKIPPED])
    return reduce_record(record)
