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
Frequency response data: the result object of every estimator.

Modelled on python-control's ``FrequencyResponseData``: the response is an array shaped
``(n_out, n_in, n_freq)``; frequencies are kept in Hz (``freq_hz``) with ``omega`` in rad/s
for convenience. Optional variances (same shape, real) carry the uncertainty of the estimate.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from frf_ident.core.estimation.distortion import DistortionLines
from frf_ident.core.estimation.missing import MissingSamples
from frf_ident.core.estimation.robust_levels import RobustLpmLevels
from frf_ident.core.jsonable import jsonable
import numpy as np

__all__ = ['FrequencyResponse']


@dataclass
class FrequencyResponse:
    """
    A MIMO frequency response estimate P_hat(w_k) (eq. 7, or a best linear approximation).

    The constructor converts its arguments to numpy arrays and checks their shapes; a 1-D
    ``response`` is taken as a SISO response. The variances are those of the complex
    estimate, E|P_hat - P|^2.

    Parameters
    ----------
    freq_hz : array_like, shape (n_freq,)
        Frequencies in Hz, in increasing order.
    response : array_like, shape (n_out, n_in, n_freq) or (n_freq,)
        Complex response of every output/input channel.
    inputs, outputs : list of str, optional
        Channel names (n_in and n_out of them); default ``u0, u1, ...`` and ``y0, y1, ...``.
    noise_variance : array_like, shape (n_out, n_in, n_freq), optional
        Variance of the estimate due to noise (from the periods of a multisine).
    total_variance : array_like, shape (n_out, n_in, n_freq), optional
        Variance due to noise plus stochastic nonlinear distortions (from the realisations
        of a multisine best linear approximation, Sec. 4.3).
    meta : dict, optional
        Free-form description (design, method, condition numbers ...).

    Raises
    ------
    ValueError
        ``response`` is not shaped (n_out, n_in, n_freq), the number of names does not match
        it, or a variance has another shape than ``response``.

    """

    freq_hz: np.ndarray
    response: np.ndarray
    inputs: list[str] = field(default_factory=list)
    outputs: list[str] = field(default_factory=list)
    noise_variance: np.ndarray | None = None
    total_variance: np.ndarray | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.freq_hz = np.asarray(self.freq_hz, dtype=float).reshape(-1)
        resp = np.asarray(self.response, dtype=complex)
        if resp.ndim == 1:
            resp = resp.reshape(1, 1, -1)
        if resp.ndim != 3 or resp.shape[2] != self.freq_hz.size:
            raise ValueError(
                f'response must be shaped (n_out, n_in, n_freq={self.freq_hz.size}), '
                f'got {resp.shape=}')
        self.response = resp
        n_out, n_in, _ = resp.shape
        if not self.inputs:
            self.inputs = [f'u{i}' for i in range(n_in)]
        if not self.outputs:
            self.outputs = [f'y{i}' for i in range(n_out)]
        if len(self.inputs) != n_in or len(self.outputs) != n_out:
            raise ValueError(
                f'{len(self.inputs)=} / {len(self.outputs)=} do not match response shape '
                f'{resp.shape}')
        for name in ('noise_variance', 'total_variance'):
            val = getattr(self, name)
            if val is not None:
                val = np.asarray(val, dtype=float)
                if val.shape != resp.shape:
                    raise ValueError(f'{name} shape {val.shape} != response shape {resp.shape}')
                setattr(self, name, val)

    # --- shape helpers -------------------------------------------------------------------
    @property
    def ninputs(self) -> int:
        """Return the number of inputs n_in (as ``control.FrequencyResponseData``)."""
        return self.response.shape[1]

    @property
    def noutputs(self) -> int:
        """Return the number of outputs n_out (as ``control.FrequencyResponseData``)."""
        return self.response.shape[0]

    @property
    def omega(self) -> np.ndarray:
        """Return the frequencies in rad/s, 2 pi ``freq_hz``."""
        return 2.0 * np.pi * self.freq_hz

    # --- named fields of ``meta``: what estimates.json keeps beside the response ----------
    @property
    def distortion(self) -> DistortionLines | None:
        """Return the odd/even detection-line levels of a multisine estimate (None: none)."""
        d = self.meta.get('distortion')
        return DistortionLines.from_dict(d) if isinstance(d, dict) else None

    @property
    def robust_lpm(self) -> RobustLpmLevels | None:
        """Return the noise and nonlinear variance of one realisation (None: none)."""
        d = self.meta.get('robust_lpm')
        return RobustLpmLevels.from_dict(d) if isinstance(d, dict) else None

    @property
    def missing(self) -> MissingSamples | None:
        """Return the account of the samples a gap took and the estimate filled (None: none)."""
        d = self.meta.get('missing')
        return MissingSamples.from_dict(d) if d else None

    @property
    def coherence(self) -> np.ndarray | None:
        """Return the coherence per output and line, shape (n_out, n_freq) (None: none)."""
        c = self.meta.get('coherence')
        if c is None:
            return None
        c = np.asarray(c, dtype=float)
        return c if c.shape == (self.noutputs, self.freq_hz.size) else None

    @property
    def units(self) -> dict[str, Any]:
        """Return the import map's units: ``input`` and ``outputs`` (empty for a robot's bag)."""
        u = self.meta.get('units')
        return u if isinstance(u, dict) else {}

    @property
    def method(self) -> str:
        """Return how it was estimated: the method, else the excitation's design ('' unknown)."""
        return str(self.meta.get('method', self.meta.get('design', '')))

    @property
    def notes(self) -> dict[str, Any]:
        """Return what was found and left out: ``detected``, ``left_out``, ``transient``."""
        return {k: self.meta[k] for k in ('detected', 'left_out', 'transient')
                if self.meta.get(k)}

    @property
    def dropped(self) -> dict[str, Any]:
        """Return what the estimate left out, periods or frames, and why; empty: nothing."""
        d = self.meta.get('dropped')
        return d if isinstance(d, dict) else {}

    def magnitude_db(self) -> np.ndarray:
        """
        Return the magnitude 20 log10 |P| in dB.

        Returns
        -------
        ndarray, shape (n_out, n_in, n_freq)
            Magnitude in dB; a zero response gives -6000 dB instead of -inf.

        """
        return 20.0 * np.log10(np.maximum(np.abs(self.response), 1e-300))

    def phase_deg(self, unwrap: bool = True) -> np.ndarray:
        """
        Return the phase of P in degrees.

        Parameters
        ----------
        unwrap : bool, optional
            Unwrap the phase along the frequency axis (default), else keep it in
            (-180, 180].

        Returns
        -------
        ndarray, shape (n_out, n_in, n_freq)
            Phase in degrees.

        """
        ph = np.angle(self.response)
        if unwrap:
            ph = np.unwrap(ph, axis=-1)
        return np.degrees(ph)

    def channel(self, out: int | str, inp: int | str) -> np.ndarray:
        """
        Return the complex response of one channel ``inp -> out``.

        Parameters
        ----------
        out : int or str
            Output index or name (one of ``outputs``).
        inp : int or str
            Input index or name (one of ``inputs``).

        Returns
        -------
        ndarray, shape (n_freq,)
            The response of that channel (a view, not a copy).

        Raises
        ------
        ValueError
            A name is not among ``outputs`` / ``inputs``.
        IndexError
            An index is out of range.

        """
        o = self.outputs.index(out) if isinstance(out, str) else int(out)
        i = self.inputs.index(inp) if isinstance(inp, str) else int(inp)
        return self.response[o, i]

    def channels(self, outputs: list[int | str] | None = None,
                 inputs: list[int | str] | None = None) -> 'FrequencyResponse':
        """
        Return the sub-system of some outputs and inputs (python-control's ``sys[outs, ins]``).

        Parameters
        ----------
        outputs, inputs : list of int or str, optional
            Indices or names, in the wanted order; default: all.

        Returns
        -------
        FrequencyResponse
            Those channels with their variances; ``meta`` copied shallowly.

        Raises
        ------
        ValueError
            A name is not among ``outputs`` / ``inputs``.

        """
        def idx(want, names):
            if want is None:
                return list(range(len(names)))
            return [names.index(w) if isinstance(w, str) else int(w) for w in want]
        o, i = idx(outputs, self.outputs), idx(inputs, self.inputs)

        def pick(a):
            return None if a is None else a[np.ix_(o, i)]
        return FrequencyResponse(self.freq_hz.copy(), pick(self.response),
                                 [self.inputs[k] for k in i], [self.outputs[k] for k in o],
                                 pick(self.noise_variance), pick(self.total_variance),
                                 dict(self.meta))

    def variance(self) -> np.ndarray | None:
        """
        Return the variance a fit weights this FRF by.

        Returns
        -------
        ndarray, shape (n_out, n_in, n_freq), or None
            ``total_variance`` where the estimate has it (noise and nonlinear distortion),
            else ``noise_variance``, else None.

        """
        return self.total_variance if self.total_variance is not None else self.noise_variance

    def variance_kind(self) -> str | None:
        """Return which variance :meth:`variance` gives: 'total', 'noise' or None."""
        return ('total' if self.total_variance is not None else
                'noise' if self.noise_variance is not None else None)

    def std_db(self, which: str = 'total') -> np.ndarray | None:
        """
        Return the 1-sigma magnitude uncertainty in dB.

        First-order: 20 log10(1 + sigma / |P|) with sigma the square root of the variance.

        Parameters
        ----------
        which : str, optional
            ``'total'`` (default) uses ``total_variance``; any other value (e.g. ``'noise'``)
            uses ``noise_variance``.

        Returns
        -------
        ndarray, shape (n_out, n_in, n_freq), or None
            The uncertainty in dB, or None when the chosen variance is absent.

        """
        var = self.total_variance if which == 'total' else self.noise_variance
        if var is None:
            return None
        rel = np.sqrt(np.maximum(var, 0.0)) / np.maximum(np.abs(self.response), 1e-300)
        return 20.0 * np.log10(1.0 + rel)

    def select(self, mask: np.ndarray) -> 'FrequencyResponse':
        """
        Return a copy restricted to the frequencies where ``mask`` is true.

        Parameters
        ----------
        mask : array_like of bool, shape (n_freq,)
            The frequencies to keep.

        Returns
        -------
        FrequencyResponse
            The selected lines with their variances; names are copied, ``meta`` shallowly.

        """
        mask = np.asarray(mask, dtype=bool)
        return FrequencyResponse(
            self.freq_hz[mask], self.response[..., mask], list(self.inputs), list(self.outputs),
            None if self.noise_variance is None else self.noise_variance[..., mask],
            None if self.total_variance is None else self.total_variance[..., mask],
            dict(self.meta))

    # --- serialisation -------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """
        Return a JSON-ready dict (the layout of ``frf.json``).

        Returns
        -------
        dict
            Keys ``inputs``, ``outputs``, ``freq_hz``, ``re``, ``im`` (nested lists shaped
            (n_out, n_in, n_freq)), plus ``noise_variance`` / ``total_variance`` when present
            and ``meta`` (made JSON-ready) when not empty.

        """
        d: dict[str, Any] = {
            'inputs': list(self.inputs),
            'outputs': list(self.outputs),
            'freq_hz': self.freq_hz.tolist(),
            're': self.response.real.tolist(),
            'im': self.response.imag.tolist(),
        }
        if self.noise_variance is not None:
            d['noise_variance'] = self.noise_variance.tolist()
        if self.total_variance is not None:
            d['total_variance'] = self.total_variance.tolist()
        if self.meta:
            d['meta'] = jsonable(self.meta)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> 'FrequencyResponse':
        """
        Build a FrequencyResponse from the dict of :meth:`to_dict`.

        Parameters
        ----------
        d : dict
            Needs ``freq_hz``, ``re`` and ``im``; ``inputs``, ``outputs``, the variances and
            ``meta`` are optional.

        Returns
        -------
        FrequencyResponse
            The response the dict describes.

        Raises
        ------
        KeyError
            ``freq_hz``, ``re`` or ``im`` is missing.
        ValueError
            The shapes do not agree (see the class).

        """
        resp = np.asarray(d['re'], dtype=float) + 1j * np.asarray(d['im'], dtype=float)
        return cls(
            np.asarray(d['freq_hz'], dtype=float), resp, list(d.get('inputs', [])),
            list(d.get('outputs', [])),
            None if d.get('noise_variance') is None else np.asarray(d['noise_variance']),
            None if d.get('total_variance') is None else np.asarray(d['total_variance']),
            dict(d.get('meta', {})))

    def to_control(self):
        """
        Convert to a python-control ``FrequencyResponseData``.

        Returns
        -------
        control.FrequencyResponseData
            Response ``response`` at ``omega`` [rad/s] with the channel names as labels;
            variances and ``meta`` are not carried over.

        Raises
        ------
        ImportError
            The optional python-control package is not installed.

        """
        import control  # optional dependency, imported lazily
        return control.FrequencyResponseData(
            self.response, self.omega, inputs=list(self.inputs), outputs=list(self.outputs))

    @classmethod
    def from_control(cls, frd) -> 'FrequencyResponse':
        """
        Convert a python-control ``FrequencyResponseData``.

        Parameters
        ----------
        frd : control.FrequencyResponseData
            Its ``omega`` [rad/s], response (``frdata``, else ``fresp``) and channel labels
            are used.

        Returns
        -------
        FrequencyResponse
            The same response with frequencies in Hz and no variances.

        """
        omega = np.asarray(frd.omega, dtype=float)
        resp = np.asarray(getattr(frd, 'frdata', None) if hasattr(frd, 'frdata') else frd.fresp,
                          dtype=complex)
        return cls(omega / (2 * np.pi), resp, list(frd.input_labels), list(frd.output_labels))
