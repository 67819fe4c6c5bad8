"""The discrete-time simulation of a linear model (``models.linear``): the zero-order,
first-order or cubic (Catmull-Rom) hold discretisation with its exact parameter
derivatives (Van Loan 1978), the per-step input vector, and the blocked propagation of the
states and their sensitivities.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import scipy.linalg

from flightid.identification.models.linear import LinearModel

HOLDS = ("foh", "zoh", "cubic")
# number of polynomial terms of each hold's input between two samples (1, tau, tau^2, ...)
_ORDER = {"zoh": 1, "foh": 2, "cubic": 4}
# Catmull-Rom: the cubic through u_{i-1}, u_i, u_{i+1}, u_{i+2} with the central-difference
# slopes at u_i and u_{i+1} (Catmull & Rom 1974), u(tau) = sum_j c_j tau^j, c = CUBIC @ w_i;
# the columns of the expm chain are int e^{A(dt-s)} B tau^j / j! ds, hence the factorials
_CUBIC = np.array([[0.0, 1.0, 0.0, 0.0],
                   [-0.5, 0.0, 0.5, 0.0],
                   [1.0, -2.5, 2.0, -0.5],
                   [-0.5, 1.5, -1.5, 0.5]]) * np.array([[1.0], [1.0], [2.0], [6.0]])


def discretize(
    A: np.ndarray, B: np.ndarray, dt: float, dA: np.ndarray, dB: np.ndarray,
    hold: str = "foh",
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Phi, Gamma and their parameter derivatives dPhi, dGamma (stacked on axis 0).

    x_{i+1} = Phi x_i + Gamma w_i with w_i = u_i ('zoh', input held over the sample),
    w_i = [u_i; u_{i+1}] ('foh', input interpolated linearly between samples) or
    w_i = [u_{i-1}; u_i; u_{i+1}; u_{i+2}] ('cubic', the Catmull-Rom cubic between u_i and
    u_{i+1}). One batched matrix exponential per parameter k of the block matrix
    (Van Loan 1978)
        [[A, 0, B, 0], [A_k, A, B_k, 0], [0, 0, 0, I/dt], [0, 0, 0, 0]] dt
    (without the last block row and column for 'zoh'; with two more links of the I/dt
    chain for 'cubic'); its blocks are Phi, dPhi/dk and the input matrices with their
    derivatives. The sensitivities are thus the exact derivatives of the discrete model
    that is simulated.

    Parameters
    ----------
    A : numpy.ndarray
        Continuous-time state matrix, shape (n, n), 1/s.
    B : numpy.ndarray
        Continuous-time input matrix, shape (n, m).
    dt : float
        Sample interval, s.
    dA : numpy.ndarray
        dA/dk for each of the npar parameters, shape (npar, n, n); npar may be 0.
    dB : numpy.ndarray
        dB/dk, shape (npar, n, m).
    hold : str, optional
        'foh' (default), 'zoh' or 'cubic'.

    Returns
    -------
    phi : numpy.ndarray
        Transition matrix, shape (n, n).
    gamma : numpy.ndarray
        Input matrix of w_i, shape (n, m) ('zoh'), (n, 2 m) ('foh') or (n, 4 m) ('cubic').
    dphi : numpy.ndarray
        dPhi/dk, shape (npar, n, n).
    dgamma : numpy.ndarray
        dGamma/dk, shape (npar, n, m), (npar, n, 2 m) or (npar, n, 4 m).

    Raises
    ------
    ValueError
        ``hold`` is not one of ``HOLDS``.
    """
    if hold not in HOLDS:
        raise ValueError(f"hold must be one of {', '.join(HOLDS)}, got {hold!r}")
    n, m = B.shape
    npar = dA.shape[0]
    order = _ORDER[hold]
    batch = max(npar, 1)
    size = 2 * n + order * m
    big = np.zeros((batch, size, size))
    big[:, :n, :n] = A * dt
    big[:, n:2 * n, n:2 * n] = A * dt
    big[:, :n, 2 * n:2 * n + m] = B * dt
    if npar:
        big[:, n:2 * n, :n] = dA * dt
        big[:, n:2 * n, 2 * n:2 * n + m] = dB * dt
    for j in range(order - 1):  # the chain I/dt: tau^(j+1) / (j+1)!
        rows = slice(2 * n + j * m, 2 * n + (j + 1) * m)
        big[:, rows, 2 * n + (j + 1) * m:2 * n + (j + 2) * m] = np.eye(m)
    # a trial step of an optimiser may make A explode: the non-finite matrices that follow
    # are rejected by the caller's cost, not warned about
    with np.errstate(over="ignore", invalid="ignore"):
        e = scipy.linalg.expm(big)
    phi = e[0, :n, :n]
    dphi = e[:npar, n:2 * n, :n]
    g = [e[:, :, 2 * n + j * m:2 * n + (j + 1) * m] for j in range(order)]
    if hold == "zoh":
        gam = g[0]
    elif hold == "foh":  # x_{i+1} = Phi x_i + G0 u_i + G1 (u_{i+1} - u_i)
        gam = np.concatenate([g[0] - g[1], g[1]], axis=2)
    else:  # sum_j G_j c_j with c = _CUBIC @ [u_{i-1}, u_i, u_{i+1}, u_{i+2}]
        gam = np.concatenate([sum(_CUBIC[j, k] * g[j] for j in range(4)) for k in range(4)],
                             axis=2)
    return phi, gam[0, :n], dphi, gam[:npar, n:2 * n]


def hold_inputs(u: np.ndarray, hold: str) -> np.ndarray:
    """The per-step input vector w_i of ``discretize``: u_i ('zoh'), [u_i, u_{i+1}] ('foh')
    or [u_{i-1}, u_i, u_{i+1}, u_{i+2}] ('cubic').

    Parameters
    ----------
    u : numpy.ndarray
        Inputs per sample, shape (N, m), SI units.
    hold : str
        'zoh', 'foh' or 'cubic'.

    Returns
    -------
    numpy.ndarray
        w, shape (N, m) ('zoh'), (N, 2 m) ('foh'; the last sample repeats u_{N-1}) or
        (N, 4 m) ('cubic'; the samples before the first and after the last extrapolated
        linearly, so that the end intervals are linear).
    """
    if hold == "zoh":
        return u
    if hold == "foh":
        return np.concatenate([u, np.vstack([u[1:], u[-1:]])], axis=1)
    if len(u) < 2:
        return np.concatenate([u, u, u, u], axis=1)
    ext = np.vstack([2 * u[:1] - u[1:2], u, 2 * u[-1:] - u[-2:-1], 2 * u[-1:] - u[-2:-1]])
    return np.concatenate([ext[:-3], ext[1:-2], ext[2:-1], ext[3:]], axis=1)


def propagate(phi: np.ndarray, forcing: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """x_{i+1} = phi x_i + forcing_i from x0.

    Blocked recursion so that Python loops run about 2 sqrt(N) times instead of N: within
    blocks of L samples the zero-state responses of all blocks are advanced together, the
    block-start states are chained with phi^L, and phi^j x_block is added back.

    Parameters
    ----------
    phi : numpy.ndarray
        Transition matrix, shape (n, n).
    forcing : numpy.ndarray
        Forcing per step, shape (N, n) or (N, n, k) for k columns propagated together.
    x0 : numpy.ndarray
        Initial state, shape (n,) or (n, k) to match ``forcing``.

    Returns
    -------
    numpy.ndarray
        States x_0 ... x_{N-1}, same shape as ``forcing``.
    """
    squeeze = forcing.ndim == 2
    f = forcing[:, :, None] if squeeze else forcing
    x0 = np.asarray(x0, dtype=float).reshape(f.shape[1], f.shape[2])
    n_samples, n, k = f.shape
    size = max(1, int(np.ceil(np.sqrt(n_samples))))
    blocks = -(-n_samples // size)
    padded = np.zeros((blocks * size, n, k))
    padded[:n_samples] = f
    fb = padded.reshape(blocks, size, n, k)
    local = np.empty((blocks, size, n, k))
    state = np.zeros((blocks, n, k))
    for j in range(size):
        local[:, j] = state
        state = phi @ state + fb[:, j]
    powers = np.empty((size + 1, n, n))
    powers[0] = np.eye(n)
    for j in range(size):
        powers[j + 1] = phi @ powers[j]
    starts = np.empty((blocks, n, k))
    starts[0] = x0
    for b in range(blocks - 1):
        starts[b + 1] = powers[size] @ starts[b] + state[b]
    out = (np.matmul(powers[None, :size], starts[:, None]) + local).reshape(-1, n, k)
    out = out[:n_samples]
    return out[:, :, 0] if squeeze else out


def simulate(model: LinearModel, values: Mapping[str, float], time: np.ndarray,
             inputs: np.ndarray, x0: np.ndarray | None = None, hold: str = "foh") -> np.ndarray:
    """Outputs of ``model`` at ``values`` for inputs sampled at ``time``.

    Parameters
    ----------
    model : LinearModel
        The linear model.
    values : mapping of str to float
        Parameter values (missing ones take the model's start values).
    time : numpy.ndarray
        Sample times, s, shape (N,); the mean interval is the sample interval.
    inputs : numpy.ndarray
        Inputs in the model's order and SI units, shape (N, m).
    x0 : numpy.ndarray or None, optional
        Initial state, shape (n,), SI units; default zero.
    hold : str, optional
        'foh' (default) or 'zoh'.

    Returns
    -------
    numpy.ndarray
        Outputs in the model's order and SI units, shape (N, ny).
    """
    time = np.asarray(time, dtype=float)
    u = np.column_stack([np.asarray(inputs, dtype=float).reshape(len(time), -1),
                         np.ones(len(time))])
    A, B, C, D = model.matrices(values)
    x0 = np.zeros(A.shape[0]) if x0 is None else np.asarray(x0, dtype=float)
    return simulate_matrices(A, B, C, D, float(np.mean(np.diff(time))), u, hold_inputs(u, hold), x0,
                     hold)


def simulate_matrices(A, B, C, D, dt, u, w, x0, hold) -> np.ndarray:
    """Outputs of the state-space matrices A, B, C, D sampled every ``dt`` s.

    Parameters
    ----------
    A : numpy.ndarray
        State matrix, shape (n, n), 1/s.
    B : numpy.ndarray
        Input matrix, shape (n, m + 1), the last column for the constant 1.
    C : numpy.ndarray
        Output matrix, shape (ny, n).
    D : numpy.ndarray
        Feed-through matrix, shape (ny, m + 1).
    dt : float
        Sample interval, s.
    u : numpy.ndarray
        Inputs with the constant 1 last, shape (N, m + 1), SI units.
    w : numpy.ndarray
        Per-step input vector of ``u`` (``hold_inputs``).
    x0 : numpy.ndarray
        Initial state, shape (n,).
    hold : str
        'foh' or 'zoh', as used for ``w``.

    Returns
    -------
    numpy.ndarray
        Outputs, shape (N, ny).
    """
    phi, gam, _, _ = discretize(A, B, dt, np.zeros((0, *A.shape)), np.zeros((0, *B.shape)),
                                hold)
    x = propagate(phi, w @ gam.T, x0)
    return x @ C.T + u @ D.T



def stacked_product(mats: np.ndarray, x: np.ndarray) -> np.ndarray:
    """out[i, a, k] = sum_b mats[k, a, b] x[i, b], as one matrix product.

    Parameters
    ----------
    mats : numpy.ndarray
        Stack of K matrices, shape (K, a, b).
    x : numpy.ndarray
        Vectors, shape (N, b).

    Returns
    -------
    numpy.ndarray
        Products, shape (N, a, K); (N, a, 0) when K is 0.
    """
    k, a, b = mats.shape
    if k == 0:
        return np.zeros((x.shape[0], a, 0))
    return (x @ mats.reshape(k * a, b).T).reshape(x.shape[0], k, a).transpose(0, 2, 1)
