# Copyright 2026 frf_ident developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
The LPM of time records: DFT frames, the direct or indirect estimate, the Welch H1 beside it.

- :func:`lpm_frf` — time records of y, u (and the reference r): DFT frames, the direct or,
  with r, the indirect estimate P = G_yr G_ur^-1 with its propagated variance, averaged over
  frames; beside it the Welch H1 baseline (:func:`welch_h1`)
- :class:`LpmAccumulator` — the same, frame by frame, for streamed records; a frame whose
  outputs miss samples is estimated with them as unknowns
  (:func:`~frf_ident.core.estimation.missing_lpm.lpm_missing`)

The LPM of one frame's spectra is :func:`~frf_ident.core.estimation.lpm.lpm_lines`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from frf_ident.core.estimation.frd import FrequencyResponse
from frf_ident.core.estimation.lpm import DEFAULT_ORDER, lpm_lines, LpmLines
from frf_ident.core.estimation.missing import MissingSamples
from frf_ident.core.estimation.missing_lpm import lpm_missing
from frf_ident.errors import EstimationError
import numpy as np
from scipy import signal

__all__ = ['BAND_POWER', 'DEFAULT_FRAME_SAMPLES', 'DIRECT_WARNING', 'EXCITED_FRACTION',
           'LpmAccumulator', 'LpmResult', 'WELCH_SEGMENTS', 'lpm_frf', 'welch_h1',
           'welch_nperseg']

#: LPM frame length [samples]: long records are cut into frames this long (resolution
#: fs / frame: 0.03 Hz at 1 kHz, 16384 lines per channel in frf.json), each estimated alone
#: and the frames averaged; a shorter record is one frame
DEFAULT_FRAME_SAMPLES = 32768

#: the band that holds this fraction of the regressor's power (r for the indirect estimate,
#: u for the direct one) is reported: outside it the estimate rests on little excitation
BAND_POWER = 0.99

#: lines whose input power (trace of S_uu; for the LPM the regressor's, r or u) is at least
#: this fraction of the largest line's count as excited (the band the coherence summary is
#: taken over; LPM lines below it are dropped: no excitation, no estimate)
EXCITED_FRACTION = 1e-3

#: Welch segments the H1 baseline averages when the record allows (its resolution is then
#: 8 / record length); Hann window, 50 % overlap (scipy.signal defaults)
WELCH_SEGMENTS = 8


def _frame_spectra(x: np.ndarray) -> np.ndarray:
    """Return the DFT of a frame (N, n) -> (n, N//2 + 1), scaled by 1/sqrt(N) (P&S)."""
    return np.fft.rfft(x, axis=0).T / np.sqrt(x.shape[0])


@dataclass
class LpmResult:
    """
    An LPM estimate with its Welch H1 baseline.

    Attributes
    ----------
    frf : FrequencyResponse
        P (n_out, n_in, n_freq) with ``noise_variance`` (the variance of the estimate from
        the LPM residuals, propagated through G_ur^-1 for the indirect estimate).
    noise_cov : ndarray, complex, shape (n_freq, n_z, n_z)
        Mean over frames of the LPM noise covariance of the regressed outputs ([y; u] for
        the indirect estimate, y for the direct one), DFT scaled by 1/sqrt(N).
    dof : int
        Residual degrees of freedom of each LPM window.
    frames : int
        Frames averaged.
    method : str
        'indirect' (P = G_yr G_ur^-1, uses r) or 'direct' (y on u).
    h1 : FrequencyResponse
        The Welch H1 estimate S_yu S_uu^-1 of y on u; ``meta['coherence']`` holds the
        multiple coherence of each output (n_out, n_freq).
    notes : list of str
        Warnings for the user (the bias of the direct estimate in closed loop).

    """

    frf: FrequencyResponse
    noise_cov: np.ndarray
    dof: int
    frames: int
    method: str
    h1: FrequencyResponse
    notes: list[str] = field(default_factory=list)


def welch_h1(y: np.ndarray, u: np.ndarray, fs: float, *, nperseg: int | None = None,
             inputs: list[str] | None = None, outputs: list[str] | None = None
             ) -> FrequencyResponse:
    """
    Welch H1 estimate S_yu S_uu^-1 with the multiple coherence of each output.

    Parameters
    ----------
    y : array_like, shape (N, n_out)
        Outputs.
    u : array_like, shape (N, n_in)
        Inputs.
    fs : float
        Sample rate [Hz].
    nperseg : int, optional
        Welch segment length; default :func:`welch_nperseg` of N.
    inputs, outputs : list of str, optional
        Channel names.

    Returns
    -------
    FrequencyResponse
        H1 on the Welch grid (DC dropped), ``meta['coherence']`` (n_out, n_freq) the
        multiple coherence S_yu S_uu^-1 S_uy / S_yy, ``meta['method'] = 'welch_h1'``.

    """
    y = np.asarray(y, dtype=float).reshape(len(y), -1)
    u = np.asarray(u, dtype=float).reshape(len(u), -1)
    nper = min(nperseg or welch_nperseg(y.shape[0]), y.shape[0])
    return _h1(fs, nper, *_welch_spectra(y, u, nper), inputs, outputs)


def welch_nperseg(n: int) -> int:
    """
    Return the Welch segment length of a record of ``n`` samples.

    Parameters
    ----------
    n : int
        Samples in the record (or LPM frame).

    Returns
    -------
    int
        Length of WELCH_SEGMENTS Hann segments with 50 % overlap, at least 16.

    """
    return max(16, int(n / (WELCH_SEGMENTS / 2 + 0.5)))


def _welch_spectra(y: np.ndarray, u: np.ndarray, nper: int):
    """
    Return the Welch spectra (per sample, fs = 1) of y (N, n_out) and u (N, n_in).

    Suu (F, n_in, n_in) with Suu[a, b] = E conj(U_a) U_b (scipy's csd convention), Syu
    (F, n_out, n_in) with Syu[i, a] = E conj(U_a) Y_i, Syy (F, n_out), F = nper // 2 + 1.
    """
    _, Suu = signal.csd(u.T[:, None, :], u.T[None, :, :], nperseg=nper, axis=-1)
    _, Syu = signal.csd(u.T[None, :, :], y.T[:, None, :], nperseg=nper, axis=-1)
    _, Syy = signal.welch(y.T, nperseg=nper, axis=-1)
    return (np.moveaxis(Suu, -1, 0), np.moveaxis(Syu, -1, 0), np.moveaxis(Syy, -1, 0))


def _h1(fs: float, nper: int, Suu, Syu, Syy, inputs, outputs) -> FrequencyResponse:
    """Return H1 = Syu Suu^-T and the multiple coherence on the Welch grid without DC."""
    f = np.arange(nper // 2 + 1) * fs / nper
    keep = f > 0
    Suu, Syu, Syy = Suu[keep], Syu[keep], np.real(Syy[keep])
    # Y = H U: Syu[i, a] = sum_b H[i, b] Suu[a, b], i.e. Suu H^T = Syu^T
    H = np.swapaxes(np.linalg.solve(Suu, np.swapaxes(Syu, 1, 2)), 1, 2)
    explained = np.real(np.einsum('fia,fia->fi', H, np.conj(Syu)))
    coh = np.clip(explained / np.maximum(Syy, 1e-300), 0.0, 1.0)
    power = np.real(np.einsum('faa->f', Suu))
    excited = power >= EXCITED_FRACTION * power.max()
    return FrequencyResponse(f[keep], np.moveaxis(H, 0, -1), inputs or [], outputs or [],
                             meta={'method': 'welch_h1', 'nperseg': int(nper),
                                   'coherence': coh.T, 'excited': excited})


class LpmAccumulator:
    """
    LPM estimates of frames of one length, summed frame by frame (in memory or streamed).

    Every frame of ``frame_samples`` samples is estimated alone (its own transient) and the
    per-line sums of P, of its variance and of the noise covariance are kept; the result is
    their mean (the variance of a mean of independent frames: sum / frames^2). The Welch H1
    baseline sums the cross spectra of the same frames. A frame whose outputs (y, and u for
    the indirect estimate) miss samples (NaN rows) is estimated with them as unknowns
    (:func:`~frf_ident.core.estimation.missing_lpm.lpm_missing`; :attr:`missing` accounts for
    them); its regressor (u, or r) must be complete.

    Parameters
    ----------
    fs : float
        Sample rate [Hz].
    frame_samples : int
        Samples per frame (the resolution is fs / frame_samples).
    order, half_width
        As :func:`lpm_lines`.
    inputs, outputs : list of str
        Channel names of u and y.

    """

    def __init__(self, fs: float, frame_samples: int, *, order: int = DEFAULT_ORDER,
                 half_width: int | None = None, inputs: list[str] | None = None,
                 outputs: list[str] | None = None) -> None:
        self.fs = float(fs)
        self.n = int(frame_samples)
        self.order, self.half_width = order, half_width
        self.inputs, self.outputs = inputs, outputs
        self.frames = 0
        self.method: str | None = None
        self._sum: dict[str, np.ndarray | float] = {}
        self.dof = 0
        #: the account of the frames' estimated missing output samples (None: none)
        self.missing: MissingSamples | None = None

    def add(self, y: np.ndarray, u: np.ndarray, r: np.ndarray | None = None) -> int:
        """
        Estimate every whole frame of a record and add it; return the samples used.

        Parameters
        ----------
        y : array_like, shape (N, n_out)
            Outputs.
        u : array_like, shape (N, n_in)
            Inputs.
        r : array_like, shape (N, n_in), optional
            Reference (the indirect estimate); None: the direct estimate.

        Returns
        -------
        int
            Samples used (whole frames from the start; the rest is left).

        Raises
        ------
        EstimationError
            The reference is given in some frames and not in others, or has another number
            of channels than u.

        """
        y = np.asarray(y, dtype=float).reshape(len(y), -1)
        u = np.asarray(u, dtype=float).reshape(len(u), -1)
        method = 'direct' if r is None else 'indirect'
        if self.method not in (None, method):
            raise EstimationError(f'LPM frames mix the {self.method} and the {method} '
                                  f'estimate; expected the reference in every frame or none')
        self.method = method
        if r is not None:
            r = np.asarray(r, dtype=float).reshape(len(r), -1)
            if r.shape[1] != u.shape[1]:
                raise EstimationError(f'reference has {r.shape[1]} channels, the inputs '
                                      f'{u.shape[1]}; expected one reference per input')
        n_frames = y.shape[0] // self.n
        for q in range(n_frames):
            sl = slice(q * self.n, (q + 1) * self.n)
            self._add_frame(y[sl], u[sl], None if r is None else r[sl])
        return n_frames * self.n

    def _add_frame(self, y, u, r) -> None:
        n_out = y.shape[1]
        z = y if r is None else np.concatenate([y, u], axis=1)     # the LPM's outputs
        gone = ~np.all(np.isfinite(z), axis=1)
        if np.any(gone):
            fit, y, u = self._missing(z, u if r is None else r, gone, n_out)
            Uf = _frame_spectra(u)[:, 1:]
        else:
            Yf, Uf = _frame_spectra(y)[:, 1:], _frame_spectra(u)[:, 1:]   # lines 1..N/2
        if r is None:
            if not np.any(gone):
                fit = lpm_lines(Yf, Uf, order=self.order, half_width=self.half_width)
            P, var = fit.G, fit.variance()
        else:
            Rf = _frame_spectra(r)[:, 1:]
            if not np.any(gone):
                fit = lpm_lines(np.concatenate([Yf, Uf]), Rf, order=self.order,
                                half_width=self.half_width)
            P, var = _indirect(fit, n_out)
        self.dof = fit.dof
        h1 = _welch_spectra(y, u, min(welch_nperseg(self.n), self.n))
        xx = np.sum(np.abs(Uf if r is None else Rf) ** 2, axis=0)      # regressor power
        for key, val in (('P', P), ('var', var), ('cov', fit.noise_cov), ('suu', h1[0]),
                         ('syu', h1[1]), ('syy', h1[2]), ('xx', xx)):
            self._sum[key] = self._sum.get(key, 0.0) + val
        self.frames += 1

    def _missing(self, z, x, gone, n_out) -> tuple[LpmLines, np.ndarray, np.ndarray]:
        """
        LPM of a frame whose outputs z miss samples: them as unknowns (missing_lpm.py).

        z holds y (and u for the indirect estimate, x = r); returns the LPM per line and y,
        u with the estimates in place (for the H1 baseline). The account of the estimates
        joins :attr:`missing`.
        """
        m = lpm_missing(z, x, gone, order=self.order, half_width=self.half_width)
        zf = np.where(gone[:, None], 0.0, z)
        zf[m.index] = m.values
        indirect = z.shape[1] > n_out
        names = list(self.outputs or [f'y{i}' for i in range(n_out)])
        if indirect:
            names += list(self.inputs or [f'u{i}' for i in range(z.shape[1] - n_out)])
        self.missing = m.account(names, z.shape[0]).merged(self.missing)
        return m.lines, zf[:, :n_out], (zf[:, n_out:] if indirect else x)

    def result(self) -> LpmResult:
        """
        Return the mean over the frames added.

        Returns
        -------
        LpmResult
            P with its variance on lines fs/N .. fs/2, and the H1 baseline.

        Raises
        ------
        EstimationError
            No whole frame was added.

        """
        if not self.frames:
            raise EstimationError(f'no whole LPM frame of {self.n / self.fs:.4g} s '
                                  f'({self.n} samples) in the record; expected a longer one')
        m = self.frames
        s = self._sum
        f = np.arange(1, self.n // 2 + 1) * self.fs / self.n
        c = np.cumsum(s['xx']) / np.sum(s['xx'])
        lo, hi = np.searchsorted(c, [(1 - BAND_POWER) / 2, (1 + BAND_POWER) / 2])
        hi = min(hi, f.size - 1)
        finite = np.all(np.isfinite(s['P']), axis=(0, 1))
        # a line without excitation has no estimate: what the polynomial puts there is the
        # neighbours' (a periodic record has power on its lines only, noise in between)
        excited = s['xx'] >= EXCITED_FRACTION * np.max(s['xx'])
        ok = finite & excited
        frf = FrequencyResponse(f[ok], s['P'][..., ok] / m, self.inputs or [],
                                self.outputs or [], s['var'][..., ok] / m ** 2, None,
                                {'method': f'lpm_{self.method}', 'order': self.order,
                                 'dof': self.dof, 'frames': m, 'frame_s': self.n / self.fs,
                                 'excitation_band_hz': [float(f[lo]), float(f[hi])],
                                 'singular_lines': int(np.count_nonzero(~finite)),
                                 'unexcited_lines': int(np.count_nonzero(finite & ~excited))})
        return LpmResult(frf, s['cov'][ok] / m, self.dof, m, self.method, self._baseline())

    def _baseline(self) -> FrequencyResponse:
        """Return H1 and coherence from the Welch spectra summed over the frames."""
        s = self._sum
        return _h1(self.fs, min(welch_nperseg(self.n), self.n), s['suu'], s['syu'], s['syy'],
                   self.inputs, self.outputs)


def _indirect(fit: LpmLines, n_out: int) -> tuple[np.ndarray, np.ndarray]:
    """
    P = G_yr G_ur^-1 and its first-order variance from an LPM of [y; u] on r.

    dP = [I, -P] dG_zr G_ur^-1, so var(P[i, j]) = (A C_Z A^H)[i, i] (B^H M B)[j, j] with
    A = [I, -P], B = G_ur^-1, C_Z the noise covariance of [y; u] and M = (K K^H)^-1.
    """
    Gz = np.moveaxis(fit.G, -1, 0)                                    # (L, n_z, n_r)
    B = np.linalg.inv(Gz[:, n_out:, :])                               # (L, n_r, n_in)
    P = Gz[:, :n_out, :] @ B                                          # (L, n_out, n_in)
    A = np.concatenate([np.broadcast_to(np.eye(n_out), P.shape[:1] + (n_out, n_out)), -P],
                       axis=2)
    left = np.real(np.einsum('lia,lab,lib->li', A, fit.noise_cov, np.conj(A)))
    right = np.real(np.einsum('lmj,lmn,lnj->lj', np.conj(B), fit.minv, B))
    var = left[:, :, None] * right[:, None, :]
    return np.moveaxis(P, 0, -1), np.moveaxis(var, 0, -1)


def lpm_frf(y: np.ndarray, u: np.ndarray, fs: float, *, r: np.ndarray | None = None,
            order: int = DEFAULT_ORDER, half_width: int | None = None,
            frame_samples: int = DEFAULT_FRAME_SAMPLES, inputs: list[str] | None = None,
            outputs: list[str] | None = None) -> LpmResult:
    """
    LPM estimate of the FRF from u to y, indirect through r when given; H1 beside it.

    With the reference r (closed loop), the LPM of [y; u] on r gives G_yr and G_ur and
    P = G_yr G_ur^-1: noise fed back through the controller is uncorrelated with r and does
    not bias P. Without r the direct LPM of y on u is biased towards -1/C wherever output
    noise is fed back (a note in ``notes`` says so).

    Parameters
    ----------
    y : array_like, shape (N, n_out)
        Outputs.
    u : array_like, shape (N, n_in)
        Inputs.
    fs : float
        Sample rate [Hz].
    r : array_like, shape (N, n_in), optional
        Reference signals, one per input.
    order, half_width
        As :func:`lpm_lines`.
    frame_samples : int
        Frame length; a record shorter than one frame is one frame.
    inputs, outputs : list of str, optional
        Channel names.

    Returns
    -------
    LpmResult
        The estimate, its noise covariance and dof, and the Welch H1 baseline.

    """
    y = np.asarray(y, dtype=float).reshape(len(y), -1)
    n = min(y.shape[0], int(frame_samples))
    acc = LpmAccumulator(fs, n, order=order, half_width=half_width, inputs=inputs,
                         outputs=outputs)
    acc.add(y, u, r)
    res = acc.result()
    if r is None:
        res.notes.append(DIRECT_WARNING)
    return res


#: the one-line warning of the direct estimate (no reference recorded)
DIRECT_WARNING = ('no reference recorded: direct LPM of the outputs on the inputs, biased '
                  'towards -1/C where output noise is fed back by the controller')
