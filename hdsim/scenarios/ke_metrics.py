"""Metrics of a driven run: pure functions over time series (SI in, SI out).

Arrays carry a leading batch axis ``(M, nt)``; the WG angle may be ``(nt,)`` (a
prescribed motion, shared by all samples) or ``(M, nt)``. Every function returns
``(M,)`` (or a list of ``(M,)``). Definitions (docs/tutorial-kinematic-error.md):

- **Deviation** ``q = θ_out − θ_wg / N`` (the kinematic error of docs/measurements.md).
- **Transmission accuracy**: over one output revolution without reversal, the largest
  positive plus the largest negative deviation of θ_out from θ_wg/N, i.e. the
  peak-to-peak of ``q`` over the last ``2πN`` of WG travel in the window. A constant
  windup under a constant load shifts ``q`` and drops out.
- **Lost motion on reversal**: the mean gap between the deviation curves of the forward
  and the reverse pass at the same WG angle, over the WG angles both passes cover.
  The kinematic error, a function of position, cancels; what is left is the twist
  reversed by the load plus backlash and hysteresis.
- **Windup**: mean twist of the elastic path (backlash, slip and spring) over a pass.
- **Order spectrum**: amplitude of ``q`` against WG angle at orders of WG rotation
  (order 1/N is once per output revolution), from a projection over an integer number
  of output revolutions at constant speed.
"""

from __future__ import annotations

import numpy as np

TWO_PI = 2.0 * np.pi


def _rows(x, M):
    x = np.asarray(x, dtype=float)
    return np.broadcast_to(x, (M, x.shape[-1]))


def _mask(t, window):
    a, b = window
    return (t >= a - 1e-12) & (t <= b + 1e-12)


def order_label(order: float) -> str:
    """``2`` → "2", ``0.5`` → "0p5" (metric-name safe)."""
    return f"{order:g}".replace(".", "p").replace("-", "m")


def window_mean(t, x, window):
    """Mean of a signal over a time window, per sample.

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s].
    x : numpy.ndarray, shape (M, nt)
        The signal (any unit).
    window : tuple
        (start, end) [s].

    Returns
    -------
    numpy.ndarray, shape (M,)
        The mean, in the unit of ``x``.
    """
    m = _mask(t, window)
    return np.mean(np.asarray(x)[:, m], axis=1)


def _last_revolution(wg, mask, N):
    """Mask of the samples in the last 2π|N| of WG travel inside ``mask``."""
    idx = np.flatnonzero(mask)
    end = wg[idx[-1]]
    keep = np.abs(wg - end) <= TWO_PI * abs(N) * (1.0 + 1e-9)
    return mask & keep


def transmission_accuracy(t, wg, q, window, N):
    """Transmission accuracy: peak-to-peak of the deviation over the last output revolution in a window.

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s].
    wg : numpy.ndarray, shape (nt,) or (M, nt)
        WG angle [rad].
    q : numpy.ndarray, shape (M, nt)
        Deviation θ_out − θ_wg/N [rad].
    window : tuple
        (start, end) [s] of a pass without reversal.
    N : float
        Transmission ratio.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Transmission accuracy [rad].
    """
    q = np.asarray(q)
    M = q.shape[0]
    wg = _rows(wg, M)
    out = np.empty(M)
    base = _mask(t, window)
    for m in range(M):
        sel = _last_revolution(wg[m], base, N)
        out[m] = np.max(q[m, sel]) - np.min(q[m, sel])
    return out


def lost_motion_on_reversal(t, wg, q, forward, reverse, points: int = 4000):
    """Lost motion on reversal: the mean gap between the forward and reverse deviation curves.

    |mean(q_forward(θ_wg) − q_reverse(θ_wg))| over the WG angles both passes cover.

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s].
    wg : numpy.ndarray, shape (nt,) or (M, nt)
        WG angle [rad].
    q : numpy.ndarray, shape (M, nt)
        Deviation [rad].
    forward, reverse : tuple
        (start, end) [s] of the two passes.
    points : int
        WG-angle grid points the curves are compared on.

    Returns
    -------
    numpy.ndarray, shape (M,)
        Lost motion [rad]; NaN where the passes share no WG angle.
    """
    q = np.asarray(q)
    M = q.shape[0]
    wg = _rows(wg, M)
    mf, mr = _mask(t, forward), _mask(t, reverse)
    out = np.empty(M)
    for m in range(M):
        af, qf = wg[m, mf], q[m, mf]
        ar, qr = wg[m, mr], q[m, mr]
        lo = max(af.min(), ar.min())
        hi = min(af.max(), ar.max())
        if hi <= lo:
            out[m] = np.nan
            continue
        grid = np.linspace(lo, hi, points)
        of, orr = np.argsort(af), np.argsort(ar)
        gap = np.interp(grid, af[of], qf[of]) - np.interp(grid, ar[orr], qr[orr])
        out[m] = abs(np.mean(gap))
    return out


def order_amplitudes(t, wg, q, window, N, orders, samples_per_rev: int = 64):
    """Amplitude of the deviation at given orders of WG rotation.

    The window is cut to a whole number of output revolutions of WG travel (at least
    one WG revolution if shorter), ``q`` resampled uniformly in WG angle, and each order
    projected: ``a_k = 2/n |Σ q_i exp(−j k θ_i)|`` (exact for orders on the grid).

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s].
    wg : numpy.ndarray, shape (nt,) or (M, nt)
        WG angle [rad].
    q : numpy.ndarray, shape (M, nt)
        Deviation [rad].
    window : tuple
        (start, end) [s], at constant speed.
    N : float
        Transmission ratio.
    orders : list of float
        Orders of WG rotation (1/N: once per output revolution).
    samples_per_rev : int
        Resampling points per WG revolution.

    Returns
    -------
    list of numpy.ndarray
        One array of shape (M,) per order: amplitude [rad].
    """
    q = np.asarray(q)
    M = q.shape[0]
    wg = _rows(wg, M)
    base = _mask(t, window)
    out = [np.empty(M) for _ in orders]
    for m in range(M):
        a, x = wg[m, base], q[m, base]
        order = np.argsort(a)
        a, x = a[order], x[order]
        span = a[-1] - a[0]
        rev_out = TWO_PI * abs(N)
        length = np.floor(span / rev_out * (1 + 1e-9)) * rev_out
        if length == 0.0:
            length = np.floor(span / TWO_PI) * TWO_PI
        n = max(int(round(length / TWO_PI * samples_per_rev)), 8)
        grid = a[-1] - length + length * np.arange(n) / n
        y = np.interp(grid, a, x)
        y = y - np.mean(y)
        for j, k in enumerate(orders):
            out[j][m] = 2.0 / n * np.abs(np.sum(y * np.exp(-1j * k * grid)))
    return out


def order_spectrum(t, wg, q, window, N, max_order: float = 8.0, samples_per_rev: int = 64):
    """Order spectrum of the deviation of sample 0, by FFT over whole output revolutions.

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s].
    wg : numpy.ndarray, shape (nt,) or (M, nt)
        WG angle [rad].
    q : numpy.ndarray, shape (M, nt)
        Deviation [rad].
    window : tuple
        (start, end) [s], at constant speed.
    N : float
        Transmission ratio.
    max_order : float
        Highest order of WG rotation returned.
    samples_per_rev : int
        Resampling points per WG revolution.

    Returns
    -------
    tuple of numpy.ndarray
        (orders of WG rotation, amplitudes [rad]).
    """
    q = np.asarray(q)
    wg = _rows(wg, q.shape[0])
    base = _mask(t, window)
    a, x = wg[0, base], q[0, base]
    order = np.argsort(a)
    a, x = a[order], x[order]
    rev_out = TWO_PI * abs(N)
    revs = max(np.floor((a[-1] - a[0]) / rev_out * (1 + 1e-9)), 0)
    length = revs * rev_out if revs else np.floor((a[-1] - a[0]) / TWO_PI) * TWO_PI
    n = int(round(length / TWO_PI * samples_per_rev))
    grid = a[-1] - length + length * np.arange(n) / n
    y = np.interp(grid, a, x)
    spec = np.fft.rfft(y - np.mean(y))
    orders = np.arange(spec.size) / (length / TWO_PI)
    keep = orders <= max_order
    return orders[keep], 2.0 / n * np.abs(spec[keep])


def _fft_window(t, window):
    m = _mask(t, window)
    tt = t[m]
    dt = np.diff(tt)
    if not np.allclose(dt, dt[0], rtol=1e-6, atol=1e-12):
        raise ValueError("the sweep needs uniformly sampled output")
    return m, dt[0]


def sweep_input_spectrum(t, u, window):
    """Spectrum of the input deviation on the same (zero-padded) bins as `sweep_frequency_response`.

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s]. Uniform over ``window``.
    u : numpy.ndarray, shape (nt,)
        Input, e.g. load torque [N·m].
    window : tuple
        (start, end) [s] of the sweep record.

    Returns
    -------
    numpy.ndarray
        Complex spectrum of ``u − u(start)`` (unit of ``u`` times s).
    """
    m, dt = _fft_window(t, window)
    x = np.asarray(u)[m]
    return np.fft.rfft(x - x[0], 2 * x.size)


def sweep_frequency_response(t, u, y, window):
    """Frequency response H = Y/U from a sweep that starts at rest and ends after the response decayed.

    Deviations from the first sample of the window (the operating point); the record is
    zero-padded to twice its length so the ratio is that of the transforms of the
    (finite) signals, not of their periodic extensions.

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s]. Uniform over ``window``.
    u, y : numpy.ndarray, shape (nt,)
        Input (e.g. load torque [N·m]) and output (e.g. output angle [rad]).
    window : tuple
        (start, end) [s] of the sweep record.

    Returns
    -------
    tuple of numpy.ndarray
        (f [Hz], H [unit of y per unit of u]).
    """
    m, dt = _fft_window(t, window)
    x = np.asarray(u)[m]
    z = np.asarray(y)[m]
    n = 2 * x.size
    U = np.fft.rfft(x - x[0], n)
    Y = np.fft.rfft(z - z[0], n)
    f = np.fft.rfftfreq(n, dt)
    with np.errstate(divide="ignore", invalid="ignore"):
        return f, Y / U


def settling(t, err, window, band):
    """Settling time and residual error in a window (a dwell after a move).

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s].
    err : numpy.ndarray, shape (M, nt)
        Following error [rad].
    window : tuple
        (start, end) [s].
    band : float
        Settling band [rad] around the final value.

    Returns
    -------
    tuple of numpy.ndarray, shape (M,)
        (time after the window start until ``err`` stays within ``band`` of its final
        value [s], peak-to-peak of ``err`` over the last half of the window [rad]:
        residual vibration plus whatever the position loop is still pulling in).
    """
    err = np.asarray(err)
    m = _mask(t, window)
    tt = t[m]
    settle, residual = np.empty(err.shape[0]), np.empty(err.shape[0])
    for i in range(err.shape[0]):
        e = err[i, m]
        final = np.mean(e[-max(len(e) // 10, 1):])
        outside = np.flatnonzero(np.abs(e - final) > band)
        settle[i] = (tt[outside[-1] + 1] - tt[0]) if outside.size and outside[-1] + 1 < len(tt) else (
            tt[-1] - tt[0] if outside.size else 0.0)
        half = e[len(e) // 2:]
        residual[i] = np.max(half) - np.min(half)
    return settle, residual


def load_step(t, err, before, after, band):
    """Static deflection, peak deflection and settling time of a load step.

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s].
    err : numpy.ndarray, shape (M, nt)
        Output position error [rad].
    before, after : tuple
        (start, end) [s] before and after the step.
    band : float
        Settling band [rad] around the final deflection.

    Returns
    -------
    dict
        ``deflection`` and ``peak`` [rad], ``settling_time`` [s], each of shape (M,).
    """
    err = np.asarray(err)
    mb, ma = _mask(t, before), _mask(t, after)
    ta = t[ma]
    out = {k: np.empty(err.shape[0]) for k in ("deflection", "peak", "settling_time")}
    for i in range(err.shape[0]):
        e0 = np.mean(err[i, mb][len(err[i, mb]) // 2:])
        e = err[i, ma] - e0
        final = np.mean(e[-max(len(e) // 10, 1):])
        out["deflection"][i] = final
        out["peak"][i] = e[np.argmax(np.abs(e))]
        outside = np.flatnonzero(np.abs(e - final) > band)
        out["settling_time"][i] = ta[min(outside[-1] + 1, len(ta) - 1)] - ta[0] if outside.size else 0.0
    return out


def oscillation(t, ref, out, window, frequency):
    """Gain and phase of an oscillation at its frequency, and the peak-to-peak deviation.

    Parameters
    ----------
    t : numpy.ndarray, shape (nt,)
        Sample times [s].
    ref : numpy.ndarray, shape (nt,) or (M, nt)
        Reference output angle [rad].
    out : numpy.ndarray, shape (M, nt)
        Output angle [rad].
    window : tuple
        (start, end) [s].
    frequency : float
        Oscillation frequency [Hz].

    Returns
    -------
    tuple of numpy.ndarray, shape (M,)
        (gain |Y1/R1| [-], phase ∠(Y1/R1) [rad], peak-to-peak of out − ref [rad]).
    """
    m = _mask(t, window)
    tt = t[m]
    basis = np.exp(-1j * TWO_PI * frequency * tt)
    ref = _rows(ref, np.asarray(out).shape[0])
    gain, phase, p2p = (np.empty(np.asarray(out).shape[0]) for _ in range(3))
    for i in range(len(gain)):
        r = ref[i, m] - np.mean(ref[i, m])
        y = np.asarray(out)[i, m] - np.mean(np.asarray(out)[i, m])
        h = np.sum(y * basis) / np.sum(r * basis)
        gain[i], phase[i] = np.abs(h), np.angle(h)
        d = np.asarray(out)[i, m] - ref[i, m]
        p2p[i] = np.max(d) - np.min(d)
    return gain, phase, p2p
