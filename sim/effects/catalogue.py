"""The effect catalogue: every injectable effect declared once (``CATALOGUE``).

An entry says what an effect is called, where it acts, what it does in one line, its
parameters and options, what it changes in the data, and the implementation that
injects it: a class of this package, or an ``ExternalImplementation`` (module, attribute
and parameter mapping) for the bridge's link faults and recorder clocks. The schema (``Entry``,
``Parameter``, ``ActsOn``, ...) is ``schema``'s, re-exported here.

Where an effect acts decides how it is injected (docs/effects.md, "Where effects act"):
``sensor`` on one measured channel in the sensor chain, ``mounting`` on several channels
from where the sensors sit, ``vibration`` on the IMU from the engine speed (both in
``flightid.sim.sensors.suites.measure``), ``disturbance`` in the atmosphere JSBSim flies
through (``flightid.sim.flight.disturbed``), ``link`` and ``clock`` in the bridge,
``airframe`` and ``actuator`` written into a copy of the aircraft's JSBSim XML
(``flightid.sim.augment``).

Cards name effects in three places (``SECTIONS``): a sensor channel's chain
(``effect = ...``), the sensor suite's mounting list (``effect = ...``) and
``[[disturbance]]`` (``kind = ...``), and ``[[effect]]`` (``name = ...``) for airframe and
actuator effects; ``CATALOGUE.lookup`` resolves each name to exactly one entry and says
where a name belongs if it is given in the wrong place. ``engine_vibration`` is one entry
that cards accept in both the mounting list and ``[[disturbance]]``. Sensor effects'
default magnitudes are sized for the channel ``Entry.channel`` (a pitch-rate gyro).
"""

from __future__ import annotations

from typing import Any

from flightid.sim.effects.airframe import (
    AXES_CHOICES,
    DERIVATIVES,
    FORM_CHOICES,
    SCHEDULE_CHOICES,
    SURFACE_CHOICES,
    ActuatorBias,
    ActuatorLag,
    Backlash,
    CgOffset,
    ControlEffectiveness,
    Deadband,
    DerivativeDelta,
    DerivativeTable,
    InertiaScale,
    MassScale,
    RateLimit,
    TailIce,
    ThrustMoment,
)
from flightid.sim.effects.clock import RECORDER_CLOCK
from flightid.sim.effects.disturbance import INTENSITIES, TURBULENCE_MODELS, Gust, Turbulence, Wind
from flightid.sim.effects.link import link_fault
from flightid.sim.effects.mounting import MISALIGNMENT_AXES, LeverArm, Misalignment, Vanes
from flightid.sim.effects.schema import (
    ARRIVAL_TIMES,
    CH,
    INF,
    PACKET_BYTES,
    RESERVED,
    SECTIONS,
    TIME_STAMPS,
    WHERE,
    ActsOn,
    Catalogue,
    Entry,
    Option,
    Parameter,
    Section,
)
from flightid.sim.effects.sensor import (
    Bias,
    Delay,
    Drift,
    Lag,
    LowPass,
    Quantization,
    RandomWalk,
    Sample,
    Saturation,
    ScaleFactor,
    SecondOrder,
    WhiteNoise,
)
from flightid.sim.effects.vibration import AXES, EngineVibration
from flightid.units import DEG

# -- the declarations ------------------------------------------------------------------


def _p(name: str, unit: str, meaning: str, default: float, low: float = -INF,
       high: float = INF, neutral: float | None = 0.0, low_open: bool = False) -> Parameter:
    return Parameter(name, unit, meaning, default, low, high, neutral, low_open)


def _sensor(name: str, cls: type, description: str, *params: Parameter) -> Entry:
    return Entry(name, ActsOn.SENSOR, description, params, cls, ("q",), channel="q")


_VANE = "vane position from the CG, body {axis} (m)"
_SURFACE = Option("surface", SURFACE_CHOICES, "de", "the control surface (project signs)")


def _actuator(name: str, cls: type, description: str, changes: tuple[str, ...],
              *params: Parameter) -> Entry:
    return Entry(name, ActsOn.ACTUATOR, description, params, cls, changes, options=(_SURFACE,))

CATALOGUE = Catalogue((
    # -- sensor: one channel, in the order a chain usually applies them -------------------
    _sensor("noise", WhiteNoise, "additive white Gaussian noise",
            _p("sigma", CH, "standard deviation", 0.005, 0.0)),
    _sensor("bias", Bias, "constant offset (null shift)",
            _p("value", CH, "offset", 0.01)),
    _sensor("drift", Drift, "bias growing linearly from the first sample",
            _p("rate", f"{CH}/s", "growth rate of the bias", 0.002)),
    _sensor("random_walk", RandomWalk, "bias random walk (gyro rate random walk), zero at "
            "the first sample",
            _p("sigma", f"{CH}/sqrt(s)", "increments N(0, sigma^2 dt)", 0.002, 0.0)),
    _sensor("scale", ScaleFactor, "multiplicative scale-factor error (a vane's K, a gain "
            "error)",
            # (0, 2]: a gain error doubling the signal, or a sign or unit error, is no
            # scale factor (a vane's K is 1.0-1.3, Morelli & Klein 2016 §10.2)
            _p("factor", "1", "measured = factor x true", 1.05, 0.0, 2.0, neutral=1.0,
               low_open=True)),
    _sensor("quantize", Quantization, "rounding to whole counts of the converter",
            _p("resolution", CH, "one count (0: none)", 0.002, 0.0)),
    _sensor("saturate", Saturation, "clipping at the sensor's range",
            _p("limit", CH, "range +-limit (inf: unlimited); the default clips a pitch "
               "doublet's response", 0.05, 0.0, neutral=INF, low_open=True)),
    _sensor("delay", Delay, "pure time delay (tubing, processing, transmission)",
            _p("tau", "s", "delay", 0.05, 0.0)),
    _sensor("lag", Lag, "first-order lag 1 / (tau s + 1) (sensor or tubing time constant)",
            _p("tau", "s", "time constant", 0.05, 0.0)),
    _sensor("second_order", SecondOrder, "second-order sensor dynamics (a flow vane)",
            _p("wn", "rad/s", "natural frequency (inf: none)", 30.0, 0.0, neutral=INF,
               low_open=True),
            _p("zeta", "1", "damping ratio", 0.7, 0.0, neutral=None, low_open=True)),
    _sensor("lowpass", LowPass, "causal Butterworth low-pass filter",
            _p("cutoff", "Hz", "cutoff frequency (inf: none)", 5.0, 0.0, neutral=INF,
               low_open=True),
            _p("order", "1", "filter order (whole number)", 2.0, 1.0, neutral=None)),
    _sensor("sample", Sample, "sampling at a lower rate, optionally anti-aliased; "
            "aliases what lies above rate/2",
            _p("rate", "Hz", "sample rate (inf: continuous)", 25.0, 0.0, neutral=INF,
               low_open=True),
            _p("offset", "s", "first sample after the record's start", 0.0, 0.0),
            _p("antialias", "Hz", "anti-alias Butterworth cutoff (0: none)", 0.0, 0.0),
            _p("order", "1", "anti-alias filter order (whole number)", 4.0, 1.0, neutral=None)),
    # -- mounting ------------------------------------------------------------------------
    Entry("lever_arm", ActsOn.MOUNTING, "accelerometers away from the CG: tangential and "
          "centripetal accelerations of the rotation",
          (_p("x", "m", "accelerometer position from the CG, body x (forward)", 0.3),
           _p("y", "m", "accelerometer position from the CG, body y (right)", 0.05),
           _p("z", "m", "accelerometer position from the CG, body z (down)", 0.2)),
          LeverArm, ("ax", "ay", "az")),
    Entry("vanes", ActsOn.MOUNTING, "alpha/beta vanes away from the CG (rotation-induced "
          "flow) with upwash and sidewash flow amplification",
          (*(_p(f"{a}_{axis}", "m", f"{a} " + _VANE.format(axis=axis), d)
             for a in ("alpha", "beta") for axis, d in zip("xyz", (1.0, 0.0, 0.0), strict=True)),
           _p("upwash", "1", "alpha measured = (1 + upwash) x local alpha", 0.05, -1.0,
              low_open=True),
           _p("sidewash", "1", "beta measured = (1 + sidewash) x local beta", 0.05, -1.0,
              low_open=True)),
          Vanes, ("alpha", "beta")),
    Entry("misalignment", ActsOn.MOUNTING, "IMU triad (gyros and accelerometers) rotated "
          "about one body axis (mounting error)",
          # |angle| <= 0.1 rad (5.7 deg): a triad mounted visibly crooked; a bench
          # alignment leaves a few tenths of a degree (Jategaonkar 2015, ch. 10)
          (_p("angle", "rad", "rotation about the axis, right-handed", 0.02, -0.1, 0.1),),
          Misalignment, ("p", "r", "ax", "az"),
          options=(Option("axis", MISALIGNMENT_AXES, "y",
                          "body axis of the rotation (y: p and r, ax and az mixed)"),)),
    # -- vibration -------------------------------------------------------------------------
    Entry("engine_vibration", ActsOn.VIBRATION, "narrowband engine/propeller vibration "
          "lines on the IMU, following the rpm (aliases without an anti-alias filter)",
          (*(_p(a, "m/s^2", f"{a} amplitude at rpm_ref", d, 0.0)
             for a, d in zip(AXES[:3], (2.0, 2.0, 3.0), strict=True)),
           *(_p(a, "rad/s", f"{a} amplitude at rpm_ref", d, 0.0)
             for a, d in zip(AXES[3:], (2 * DEG, 2 * DEG, 1 * DEG), strict=True)),
           _p("harmonics", "1", "lines at 1..n x the rotation frequency (whole number)", 2.0,
              1.0, neutral=None),
           _p("harmonic_decay", "1", "relative amplitude of harmonic n: decay^(n-1)", 0.5,
              0.0, neutral=None),
           _p("blades", "1", "propeller blades: a blade-passing line (0: none)", 2.0, 0.0,
              neutral=None),
           _p("blade_amplitude", "1", "relative amplitude of the blade-passing line", 0.5,
              0.0, neutral=None),
           _p("gear_ratio", "1", "propeller turns per engine turn", 1.0, 0.0, neutral=None,
              low_open=True),
           _p("rpm_ref", "1/min", "engine speed of the amplitudes (0: amplitudes fixed)", 0.0,
              0.0, neutral=None),
           _p("exponent", "1", "amplitudes scale as (rpm/rpm_ref)^exponent", 0.0,
              neutral=None)),
          EngineVibration, AXES),
    # -- disturbance -----------------------------------------------------------------------
    Entry("wind", ActsOn.DISTURBANCE, "steady wind (NED, the direction the air moves "
          "towards); cards may give speed and from_deg instead",
          (_p("north", "m/s", "north component", -4.0),
           _p("east", "m/s", "east component", 3.0),
           _p("down", "m/s", "down component", 0.0)),
          Wind, ("wind_north", "wind_east", "north", "east")),
    Entry("gust", ActsOn.DISTURBANCE, "1-cosine discrete gust: rise, hold, fall "
          "(MIL-F-8785C 3.7.5)",
          (_p("start", "s", "time the gust begins", 1.0, 0.0, neutral=None),
           _p("rise", "s", "rise time (gust length / airspeed)", 0.5, 0.0, neutral=None,
              low_open=True),
           _p("hold", "s", "time at the peak", 0.0, 0.0, neutral=None),
           _p("fall", "s", "fall time", 0.5, 0.0, neutral=None, low_open=True),
           _p("north", "m/s", "peak north component", 0.0),
           _p("east", "m/s", "peak east component", 0.0),
           _p("down", "m/s", "peak down component (negative: up-gust)", -2.0)),
          Gust, ("wind_down", "alpha")),
    Entry("turbulence", ActsOn.DISTURBANCE, "continuous turbulence, Dryden or von Karman "
          "(MIL-F-8785C 3.7.2-3.7.4), or JSBSim's own",
          (_p("sigma", "m/s", "standard deviation, all axes (0 with no intensity: calm)",
              1.0, 0.0),
           _p("sigma_u", "m/s", "standard deviation along the heading (0: sigma)", 0.0, 0.0),
           _p("sigma_v", "m/s", "standard deviation to the right (0: sigma)", 0.0, 0.0),
           _p("sigma_w", "m/s", "standard deviation down (0: sigma)", 0.0, 0.0),
           _p("scale_length", "m", "scale length, all axes (0: from intensity and height)",
              300.0, 0.0, neutral=None),
           _p("scale_length_w", "m", "vertical scale length (0: scale_length)", 0.0, 0.0,
              neutral=None)),
          Turbulence, ("turb_u", "turb_v", "turb_w", "alpha", "beta"),
          options=(Option("model", TURBULENCE_MODELS, "dryden", "spectrum form"),
                   Option("intensity", ("", *INTENSITIES), "",
                          "MIL-F-8785C intensity by probability of exceedance; sets sigma "
                          "and scale lengths from the height"))),
    # -- airframe: written into a copy of the JSBSim XML (flightid.sim.augment) ----------------
    Entry("derivative_delta", ActsOn.AIRFRAME, "additive delta to one aerodynamic derivative "
          "(an extra JSBSim <function> term)",
          (_p("delta", "1/rad", "delta, per rad (per unit nondimensional rate for p q r "
              "alphadot)", 0.02),),
          DerivativeDelta, ("r", "beta"),
          options=(Option("derivative", DERIVATIVES, "Cn_beta",
                          "the derivative, C<coef>_<var> (flightid.derivatives)"),
                   Option("axes", AXES_CHOICES, "stability",
                          "axes of the delta: stability (CL CD CY, Cl Cm Cn, stability-axis "
                          "rates) or body (CX CY CZ, body rates)"),
                   Option("form", FORM_CHOICES, "linear",
                          "linear: delta x variable; even: delta x abs(variable), a term "
                          "even in the variable (one-sided slopes apart by 2 delta)"))),
    Entry("derivative_table", ActsOn.AIRFRAME, "delta to one derivative as a table in "
          "airspeed or alpha (a JSBSim <table> term): a condition-dependent error",
          (_p("delta_low", "1/rad", "delta at and below 'low', per rad (per unit "
              "nondimensional rate for p q r alphadot)", 0.02),
           _p("delta_high", "1/rad", "delta at and above 'high' (linear between)", -0.02),
           # breakpoints shape the table without sizing it: no neutral value
           _p("low", "m/s or rad", "first breakpoint (airspeed m/s, or alpha rad)", 50.0,
              neutral=None),
           _p("high", "m/s or rad", "last breakpoint, above 'low'", 75.0, neutral=None)),
          DerivativeTable, ("r", "beta"),
          options=(Option("derivative", DERIVATIVES, "Cn_beta",
                          "the derivative, C<coef>_<var> (flightid.derivatives)"),
                   Option("axes", AXES_CHOICES, "stability",
                          "axes of the delta, as derivative_delta"),
                   Option("schedule", SCHEDULE_CHOICES, "airspeed",
                          "what the table reads: true airspeed (m/s) or alpha (rad)"))),
    Entry("control_effectiveness", ActsOn.AIRFRAME, "every aerodynamic term reading a "
          "surface scaled (effectiveness loss, tail ice)",
          (_p("factor", "1", "scale of the surface's terms", 0.8, 0.0, neutral=1.0),),
          ControlEffectiveness, ("de", "q"), options=(_SURFACE,)),
    Entry("cg_offset", ActsOn.AIRFRAME, "CG moved (every mass item: CG, point masses, tanks)",
          # |shift| <= 0.5 m: a CG envelope spans some 15-20 % of the mean chord, 0.3-0.4 m
          # on the Twin Otter's 1.98 m chord (a judgement, wide for the project's aircraft)
          (_p("x", "m", "CG shift, body x (forward)", 0.05, -0.5, 0.5),
           _p("z", "m", "CG shift, body z (down)", 0.0, -0.5, 0.5)),
          CgOffset, ("de", "q")),
    Entry("mass_scale", ActsOn.AIRFRAME, "empty weight and point masses scaled (mass error)",
          # [0.5, 2]: an empty weight known to better than a factor of two (weighed)
          (_p("factor", "1", "mass scale factor", 1.1, 0.5, 2.0, neutral=1.0),),
          MassScale, ("alpha", "de")),
    Entry("inertia_scale", ActsOn.AIRFRAME, "moments of inertia scaled (Ixz by sqrt(ixx izz))",
          # [0.7, 1.45]: inertias estimated from radii of gyration or a component breakdown
          # are good to some 10-30 % (a swing test to about 5 %); beyond, a fitted factor is
          # the moment derivatives' scale, not an inertia error
          (_p("ixx", "1", "Ixx scale factor", 1.1, 0.7, 1.45, neutral=1.0),
           _p("iyy", "1", "Iyy scale factor", 1.1, 0.7, 1.45, neutral=1.0),
           _p("izz", "1", "Izz scale factor", 1.1, 0.7, 1.45, neutral=1.0)),
          InertiaScale, ("q", "p")),
    Entry("thrust_moment", ActsOn.AIRFRAME, "pitching moment proportional to thrust (thrust "
          "line, propwash)",
          # |arm| <= 1 m: a thrust line within a metre of the CG (nacelles, pylons)
          (_p("arm", "m", "N m per N of thrust, nose up positive", 0.1, -1.0, 1.0),),
          ThrustMoment, ("de",)),
    Entry("tail_ice", ActsOn.AIRFRAME, "horizontal-tail ice: pitching-moment terms reading the "
          "elevator, alpha, the pitch rate scaled (as twinotter-iced)",
          # (0, 1]: ice only takes effectiveness away (Batterson & O'Mara, NASA TM-4099,
          # 1989: elevator effectiveness, static stability and pitch damping all fall)
          (_p("elevator", "1", "scale of the pitching-moment terms reading the elevator "
              "(Cm_de)", 0.85, 0.0, 1.0, neutral=1.0, low_open=True),
           _p("stability", "1", "scale of the pitching-moment terms reading alpha (Cm_alpha)",
              0.9, 0.0, 1.0, neutral=1.0, low_open=True),
           _p("damping", "1", "scale of the pitching-moment terms reading q or alphadot "
              "(Cm_q, Cm_alphadot)", 0.9, 0.0, 1.0, neutral=1.0, low_open=True)),
          TailIce, ("q", "de")),
    # -- actuator: JSBSim <actuator> components (flightid.sim.augment) -------------------------
    _actuator("actuator_lag", ActuatorLag, "first-order lag 1/(tau s + 1) in series with the "
              "surface actuator", ("de", "q"),
              _p("tau", "s", "time constant", 0.05, 0.0)),
    _actuator("rate_limit", RateLimit, "surface rate limit in series with the actuator",
              ("de", "q"),
              _p("rate", "rad/s", "rate limit (inf: none)", 20 * DEG, 0.0, neutral=INF,
                 low_open=True)),
    _actuator("deadband", Deadband, "deadband (around zero) between the measured surface "
              "and the aerodynamics", ("q",),
              _p("width", "rad", "full width of the band", 0.5 * DEG, 0.0)),
    _actuator("backlash", Backlash, "backlash (hysteresis) between the measured surface and "
              "the aerodynamics", ("q",),
              _p("width", "rad", "full width of the hysteresis", 0.5 * DEG, 0.0)),
    _actuator("actuator_bias", ActuatorBias, "rigging bias: the aerodynamics see the measured "
              "surface plus a bias", ("de",),
              _p("bias", "rad", "aerodynamic minus measured deflection", 0.5 * DEG)),
    # -- link: the bridge's LinkFaults ---------------------------------------------------------
    Entry("corrupt", ActsOn.LINK, "bytes corrupted on the link (packets then fail their CRC)",
          (_p("probability", "1", "probability per byte", 1e-3, 0.0, 1.0),),
          link_fault("corrupt", "probability"), (PACKET_BYTES,)),
    Entry("drop", ActsOn.LINK, "whole packets lost on the link",
          (_p("probability", "1", "probability per packet", 0.01, 0.0, 1.0),),
          link_fault("drop", "probability"), (PACKET_BYTES,)),
    Entry("latency", ActsOn.LINK, "constant delivery delay of every packet",
          (_p("delay", "s", "delivery delay", 0.05, 0.0),),
          link_fault("latency", "delay"), (ARRIVAL_TIMES,)),
    Entry("jitter", ActsOn.LINK, "random delivery delay (packets stay in order)",
          (_p("sigma", "s", "standard deviation of the delay", 0.005, 0.0),),
          link_fault("jitter", "sigma"), (ARRIVAL_TIMES,)),
    # -- clock: the bridge's recorder streams ----------------------------------------------------
    Entry("clock", ActsOn.CLOCK, "a recorder's own clock: t_local = offset + (1 + drift) t",
          (_p("offset", "s", "recorder clock at sim time 0 (powered on before)", 0.84, 0.0),
           _p("drift", "1", "fractional rate error (150e-6 = 150 ppm)", 150e-6, -1.0,
              low_open=True)),
          RECORDER_CLOCK, (TIME_STAMPS,)),
))

# What an airframe can have: the range of each derivative (per rad; per unit
# nondimensional rate for p q r alphadot; project control signs, body or stability axes) a
# ``derivative_delta`` may move the model's value to. A judgement with wide margins: the
# bounds enclose the project's aircraft and the stock JSBSim DHC6 and c172p at their test
# conditions (measured with flightid.sim.jsbsim.truth.derivatives; e.g. Cm_alphadot -8.0 to 0,
# Cm_q -34.8 to -9.96, CL_alpha 4.01 to 5.62) and the light-aircraft to jet-transport
# values compiled by Heffley & Jewell (NASA CR-2144, 1972); a lift slope above 7.5 per
# rad exceeds thin-aerofoil theory's 2 pi of an infinite wing (Anderson 2017, §4.7) plus
# what fuselage and tail add. A derivative not listed is unbounded.
DERIVATIVE_RANGES: dict[str, tuple[float, float]] = {
    "CL_alpha": (0.0, 7.5), "CL_q": (-10.0, 40.0), "CL_alphadot": (-10.0, 20.0),
    "CL_de": (0.0, 1.5), "CD_alpha": (-1.0, 2.0), "CD_q": (-5.0, 5.0), "CD_de": (-0.3, 0.3),
    "Cm_alpha": (-4.0, 0.5), "Cm_q": (-80.0, 0.0), "Cm_alphadot": (-30.0, 5.0),
    "Cm_de": (-5.0, 0.0),
    "CY_beta": (-2.0, 0.0), "CY_p": (-1.0, 1.0), "CY_r": (-1.0, 2.0), "CY_da": (-0.5, 0.5),
    "CY_dr": (-0.1, 1.0),
    "Cl_beta": (-0.5, 0.1), "Cl_p": (-1.5, 0.0), "Cl_r": (-0.3, 0.8), "Cl_da": (-0.6, 0.05),
    "Cl_dr": (-0.15, 0.15),
    "Cn_beta": (-0.1, 0.8), "Cn_p": (-0.5, 0.3), "Cn_r": (-1.5, 0.05), "Cn_da": (-0.15, 0.15),
    "Cn_dr": (-0.5, 0.05),
}

# the card sections' views of the catalogue (name -> class)
EFFECTS: dict[str, type] = CATALOGUE.classes(ActsOn.SENSOR)


def effect_from_dict(d: dict[str, Any], context: str = "", unit: str | None = None):
    """Build a channel effect from ``{"effect": name, ...parameters}``; errors name the field.

    Parameters
    ----------
    d : dict
        The effect table: ``effect`` (its name) and its parameters.
    context : str, optional
        Where the table is, prefixed to field names in messages.
    unit : str, optional
        The unit of the channel it acts on (for ``_deg``/``_g`` parameters).

    Returns
    -------
    NamedEffect
        The effect.
    """
    return CATALOGUE.from_dict(d, "channel", context, unit)


__all__ = ["ARRIVAL_TIMES", "CATALOGUE", "CH", "DERIVATIVE_RANGES", "EFFECTS", "PACKET_BYTES",
           "RESERVED", "SECTIONS", "TIME_STAMPS", "WHERE", "ActsOn", "Catalogue", "Entry", "Option",
           "Parameter", "Section", "effect_from_dict"]
