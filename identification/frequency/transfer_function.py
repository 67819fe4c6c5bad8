"""Transfer-function fits to frequency responses with the CIFER cost (Tischler & Remple 2012).

A SISO model  T(s) = (b_m s^m + ... + b_0) / (s^n + a_{n-1} s^{n-1} + ... + a_0) e^{-tau s}
(a low-order equivalent system with an equivalent time delay, Tischler & Remple ch. 11;
Catterall 2003 sec. 5.3) is fitted to a measured response over the frequencies where the
coherence is at least 0.6, minimising the CIFER cost (Catterall 2003; Tischler & Remple
eq. 11.8)

    J = 20/n_w sum_w W_gamma [ W_g (|T_c| - |T|)^2 + W_p (angle T_c - angle T)^2 ],
    W_gamma = [1.58 (1 - exp(-gamma^2))]^2,  W_g = 1.0,  W_p = 0.01745,

magnitudes in dB and phases in deg (1 dB weighs as much as 7.57 deg). J <= 100 is the
usual "good fit" guideline.

Accuracy (Tischler & Remple sec. 11.6): the Cramer-Rao bound and the insensitivity of
each parameter come from the Gauss-Newton Hessian of the cost, F = sum r_theta r_theta^T
of the weighted residuals r (J = sum r^2), scaled by the residual variance
s^2 = J / (2 n_w - n_p) so that they do not depend on the arbitrary factor 20 of J:
CR_i = s sqrt((F^-1)_ii), insensitivity I_i = s / sqrt(F_ii). Guidelines: CR_i <= 20 %
and I_i <= 10 % of the value.

Units: frequency in Hz (the polynomial variable s in rad/s), delay in s, coefficients
in the response's units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from flightid.identification.frequency.response import FrequencyResponse

W_GAIN = 1.0
W_PHASE = 0.01745
COHERENCE_MIN = 0.6


def coherence_weight(coherence: np.ndarray) -> np.ndarray:
    """CIFER coherence weighting W_gamma = [1.58 (1 - exp(-gamma^2))]^2.

    Parameters
    ----------
    coherence : numpy.ndarray
        gamma^2, 1.

    Returns
    -------
    numpy.ndarray
        The weights, dimensionless; shape of ``coherence``.
    """
    return (1.58 * (1.0 - np.exp(-np.asarray(coherence, dtype=float)))) ** 2


def wrap_deg(angle: np.ndarray) -> np.ndarray:
    """Angle wrapped to (-180, 180] deg.

    Parameters
    ----------
    angle : numpy.ndarray
        Angles, deg.

    Returns
    -------
    numpy.ndarray
        The wrapped angles, deg.
    """
    return -((-np.asarray(angle) + 180.0) % 360.0 - 180.0)


def central_jacobian(fun, theta: np.ndarray, floor: float = 1e-2) -> np.ndarray:
    """Central-difference Jacobian of ``fun`` at ``theta``.

    Steps are 1e-6 of each value, with the value floored at ``floor`` (so a parameter near
    zero still gets a usable step).

    Parameters
    ----------
    fun : callable
        Maps a parameter vector to a residual vector.
    theta : numpy.ndarray
        The parameters; shape (np,).
    floor : float, optional
        The smallest magnitude a step is scaled from. Default 1e-2.

    Returns
    -------
    numpy.ndarray
        d fun / d theta; shape (len(fun(theta)), np).
    """
    base = fun(theta)
    jac = np.empty((np.size(base), theta.size))
    for j in range(theta.size):
        h = 1e-6 * max(abs(theta[j]), floor)
        up, dn = theta.copy(), theta.copy()
        up[j] += h
        dn[j] -= h
        jac[:, j] = (fun(up) - fun(dn)) / (2 * h)
    return jac


def cifer_residuals(model: np.ndarray, data: np.ndarray, coherence: np.ndarray) -> np.ndarray:
    """Weighted residuals r with sum(r^2) = CIFER cost J of complex responses on n_w points.

    Parameters
    ----------
    model : numpy.ndarray
        The model's complex response; shape (n_w,).
    data : numpy.ndarray
        The measured complex response, same unit; shape (n_w,).
    coherence : numpy.ndarray
        The measured coherence, 1; shape (n_w,).

    Returns
    -------
    numpy.ndarray
        First the n_w magnitude terms (dB), then the n_w phase terms (deg, wrapped), weighted;
        shape (2 n_w,).
    """
    n = data.size
    wg = np.sqrt(20.0 / n * coherence_weight(coherence))
    mag = 20.0 * np.log10(np.abs(model) / np.abs(data))
    phase = wrap_deg(np.degrees(np.angle(model / data)))
    return np.concatenate([wg * np.sqrt(W_GAIN) * mag, wg * np.sqrt(W_PHASE) * phase])


def cifer_cost(model: np.ndarray, data: np.ndarray, coherence: np.ndarray) -> float:
    """CIFER cost J (dimensionless; about 100 or less for a good fit).

    Parameters
    ----------
    model : numpy.ndarray
        The model's complex response; shape (n_w,).
    data : numpy.ndarray
        The measured complex response; shape (n_w,).
    coherence : numpy.ndarray
        The measured coherence; shape (n_w,).

    Returns
    -------
    float
        J.
    """
    r = cifer_residuals(model, data, coherence)
    return float(r @ r)


@dataclass
class TransferFunctionFit:
    """A fitted transfer function with equivalent delay, its accuracy and fit cost."""

    numerator: np.ndarray  # b_m ... b_0 (highest power of s first)
    denominator: np.ndarray  # 1, a_{n-1} ... a_0
    delay: float  # s
    names: list[str]
    values: np.ndarray
    std: np.ndarray  # Cramer-Rao bounds (1 sigma)
    insensitivity: np.ndarray
    covariance: np.ndarray
    cost: float  # CIFER J
    frequency: np.ndarray  # Hz, the points fitted
    input: str = "u"
    output: str = "y"
    extra: dict = field(default_factory=dict)

    def response(self, frequency: np.ndarray) -> np.ndarray:
        """Model frequency response at ``frequency`` (Hz)."""
        return _tf(self.numerator, self.denominator, self.delay,
                   2j * np.pi * np.asarray(frequency, dtype=float))

    def std_of(self, name: str) -> float:
        """Cramer-Rao bound of one parameter (same unit as its value)."""
        return float(self.std[self.names.index(name)])

    @property
    def cr_percent(self) -> np.ndarray:
        """Cramer-Rao bounds in percent of the values."""
        return 100.0 * self.std / np.maximum(np.abs(self.values), 1e-300)

    @property
    def insensitivity_percent(self) -> np.ndarray:
        """Insensitivities in percent of the values."""
        return 100.0 * self.insensitivity / np.maximum(np.abs(self.values), 1e-300)

    def poles(self) -> np.ndarray:
        """Roots of the denominator (rad/s)."""
        return np.roots(self.denominator)

    def modes(self) -> list[dict[str, float]]:
        """Each real pole or complex pair: natural frequency (rad/s), damping, their std.

        Standard deviations by first-order propagation of the denominator covariance
        through the roots (numerical Jacobian).
        """
        n_den = self.denominator.size - 1
        idx = [self.names.index(f"a{k}") for k in range(n_den)]
        cov_a = self.covariance[np.ix_(idx, idx)]
        a = np.array([self.values[i] for i in idx])

        def features(avec: np.ndarray) -> np.ndarray:
            roots = np.roots(np.concatenate([[1.0], avec[::-1]]))
            out = []
            for r in _sorted_roots(roots):
                wn = abs(r)
                out.extend([wn, -r.real / wn if wn > 0 else 1.0])
            return np.array(out)

        base = features(a)
        jac = central_jacobian(features, a, floor=1e-3)
        cov_f = jac @ cov_a @ jac.T
        std_f = np.sqrt(np.clip(np.diag(cov_f), 0.0, None))
        modes = []
        for k, r in enumerate(_sorted_roots(self.poles())):
            modes.append({
                "pole_real": float(r.real), "pole_imag": float(r.imag),
                "natural_frequency": float(base[2 * k]), "damping": float(base[2 * k + 1]),
                "natural_frequency_std": float(std_f[2 * k]),
                "damping_std": float(std_f[2 * k + 1]),
            })
        return modes


def _sorted_roots(roots: np.ndarray) -> list[complex]:
    """One representative per real pole or complex pair (upper half plane), by |root|."""
    keep = [r for r in roots if r.imag >= -1e-12 * max(1.0, abs(r))]
    return sorted(keep, key=lambda r: (abs(r), r.imag))


def _tf(num: np.ndarray, den: np.ndarray, delay: float, s: np.ndarray) -> np.ndarray:
    return np.polyval(num, s) / np.polyval(den, s) * np.exp(-s * delay)


def _unpack(theta: np.ndarray, n_num: int, n_den: int, fit_delay: bool, delay0: float):
    num = theta[: n_num + 1][::-1]  # stored b0..bm
    den = np.concatenate([[1.0], theta[n_num + 1 : n_num + 1 + n_den][::-1]])
    delay = theta[-1] if fit_delay else delay0
    return num, den, delay


def _levy(h: np.ndarray, s: np.ndarray, weight: np.ndarray, n_num: int, n_den: int,
          iterations: int = 5) -> np.ndarray:
    """Linear start values by Levy's method with Sanathanan-Koerner reweighting.

    Minimises sum w |den(s) H - num(s)|^2 / |den_prev(s)|^2 over b_0..b_m, a_0..a_{n-1}.
    """
    cols_b = [s**k for k in range(n_num + 1)]
    cols_a = [-(s**k) * h for k in range(n_den)]
    x = np.column_stack(cols_b + cols_a)
    rhs = (s**n_den) * h
    theta = np.zeros(n_num + 1 + n_den)
    scale = np.ones_like(h, dtype=float)
    for _ in range(iterations):
        wgt = np.sqrt(weight) / scale
        xa = np.vstack([(x * wgt[:, None]).real, (x * wgt[:, None]).imag])
        ya = np.concatenate([(rhs * wgt).real, (rhs * wgt).imag])
        theta, *_ = np.linalg.lstsq(xa, ya, rcond=None)
        den = np.concatenate([[1.0], theta[n_num + 1 :][::-1]])
        scale = np.maximum(np.abs(np.polyval(den, s)), 1e-12)
    return theta


def fit_transfer_function(
    response: FrequencyResponse,
    n_num: int,
    n_den: int,
    *,
    delay: bool | float = True,
    f_range: tuple[float, float] | None = None,
    coherence_min: float = COHERENCE_MIN,
    max_delay: float | None = None,
) -> TransferFunctionFit:
    """Fit num(s)/den(s) e^{-tau s} (orders n_num, n_den) to a frequency response.

    The start values come from Levy's linear fit on a grid of delays up to ``max_delay``;
    then the CIFER cost is minimised.

    Parameters
    ----------
    response : FrequencyResponse
        The measured response.
    n_num : int
        Numerator order, 0 <= n_num <= n_den.
    n_den : int
        Denominator order, >= 1.
    delay : bool or float, optional
        True to fit the equivalent delay tau (s), False for none, or a number (s) to fix it.
        Default True.
    f_range : tuple of float, optional
        (low, high) frequencies used, Hz. Default all.
    coherence_min : float, optional
        The smallest coherence of a point used. Default ``COHERENCE_MIN``.
    max_delay : float, optional
        The largest start delay tried, s. Default half a period of the highest frequency.

    Returns
    -------
    TransferFunctionFit
        The fitted transfer function and its cost.

    Raises
    ------
    ValueError
        For bad orders, a negative fixed delay or too few usable points.
    """
    if n_num < 0 or n_den < 1 or n_num > n_den:
        raise ValueError(f"need 0 <= numerator order <= denominator order >= 1, got "
                         f"{n_num}/{n_den}")
    mask = response.valid(coherence_min)
    if f_range is not None:
        mask &= (response.frequency >= f_range[0]) & (response.frequency <= f_range[1])
    n_par = n_num + 1 + n_den + (1 if delay is True else 0)
    if mask.sum() * 2 <= n_par:
        raise ValueError(
            f"only {int(mask.sum())} frequencies of {response.output}/{response.input} have "
            f"coherence >= {coherence_min}" + (f" within {f_range} Hz" if f_range else "")
            + f"; a {n_num}/{n_den} fit needs more than {n_par / 2:g}"
        )
    f = response.frequency[mask]
    h = response.response[mask]
    coh = response.coherence[mask]
    s = 2j * np.pi * f
    fit_delay = delay is True
    delay0 = 0.0 if isinstance(delay, bool) else float(delay)
    if not fit_delay and delay0 < 0:
        raise ValueError(f"delay must be >= 0 s, got {delay0}")
    tau_max = max_delay if max_delay is not None else 0.5 / f.max()
    weight = coherence_weight(coh) / np.abs(h) ** 2  # relative error, like dB

    def residuals(theta: np.ndarray) -> np.ndarray:
        num, den, tau = _unpack(theta, n_num, n_den, fit_delay, delay0)
        return cifer_residuals(_tf(num, den, tau, s), h, coh)

    lower = np.full(n_par, -np.inf)
    upper = np.full(n_par, np.inf)
    if fit_delay:
        lower[-1], upper[-1] = 0.0, max(tau_max * 2, 1e-6)
    taus = np.linspace(0.0, tau_max, 21) if fit_delay else np.array([delay0])
    best = None
    for tau in taus:
        start = _levy(h * np.exp(s * tau), s, weight, n_num, n_den)
        theta0 = np.concatenate([start, [tau]]) if fit_delay else start
        r0 = residuals(theta0)
        if best is None or r0 @ r0 < best[0]:
            best = (float(r0 @ r0), theta0)
    sol = least_squares(residuals, best[1], bounds=(lower, upper), x_scale="jac",
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=2000)
    theta = sol.x
    cost = float(sol.fun @ sol.fun)
    jac = sol.jac
    fisher = jac.T @ jac
    dof = max(sol.fun.size - n_par, 1)
    s2 = cost / dof
    cov = s2 * np.linalg.pinv(fisher)
    names = ([f"b{k}" for k in range(n_num + 1)] + [f"a{k}" for k in range(n_den)]
             + (["tau"] if fit_delay else []))
    num, den, tau = _unpack(theta, n_num, n_den, fit_delay, delay0)
    return TransferFunctionFit(
        numerator=num,
        denominator=den,
        delay=float(tau),
        names=names,
        values=theta.copy(),
        std=np.sqrt(np.clip(np.diag(cov), 0.0, None)),
        insensitivity=np.sqrt(s2 / np.maximum(np.diag(fisher), 1e-300)),
        covariance=cov,
        cost=cost,
        frequency=f,
        input=response.input,
        output=response.output,
        extra={"n_points": int(f.size), "residual_variance": s2, "converged": sol.success,
               "f_range": (float(f.min()), float(f.max()))},
    )
