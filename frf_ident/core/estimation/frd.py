"""
Frequency response data: the result object of every estimator.

Modelled on python-control's ``FrequencyResponseData``: the response is an array shaped
``(n_out, n_in, n_freq)``; frequencies are kept in Hz (``freq_hz``) with ``omega`` in rad/s
for convenience. Optional variances (same shape, real) carry the uncertainty of the estimate.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from frf_ident.core.jsonable import jsonable
import numpy as np


@dataclass
class FrequencyResponse:
    """
    A MIMO frequency response estimate.

    Attributes
    ----------
    freq_hz : (n_freq,) float array, strictly increasing.
    response : (n_out, n_in, n_freq) complex array.
    inputs, outputs : channel names (len n_in, n_out).
    noise_variance : optional (n_out, n_in, n_freq) variance of the estimate due to noise.
    total_variance : optional (n_out, n_in, n_freq) variance due to noise plus stochastic
        nonlinear distortions (multisine best linear approximation).
    meta : free-form description (design, method, condition numbers...).

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
        return self.response.shape[1]

    @property
    def noutputs(self) -> int:
        return self.response.shape[0]

    @property
    def omega(self) -> np.ndarray:
        """Frequencies in rad/s."""
        return 2.0 * np.pi * self.freq_hz

    def magnitude_db(self) -> np.ndarray:
        return 20.0 * np.log10(np.maximum(np.abs(self.response), 1e-300))

    def phase_deg(self, unwrap: bool = True) -> np.ndarray:
        ph = np.angle(self.response)
        if unwrap:
            ph = np.unwrap(ph, axis=-1)
        return np.degrees(ph)

    def channel(self, out: int | str, inp: int | str) -> np.ndarray:
        """Complex response of one channel ``inp -> out`` (index or name)."""
        o = self.outputs.index(out) if isinstance(out, str) else int(out)
        i = self.inputs.index(inp) if isinstance(inp, str) else int(inp)
        return self.response[o, i]

    def std_db(self, which: str = 'total') -> np.ndarray | None:
        """1-sigma magnitude uncertainty in dB (first-order), or None without variances."""
        var = self.total_variance if which == 'total' else self.noise_variance
        if var is None:
            return None
        rel = np.sqrt(np.maximum(var, 0.0)) / np.maximum(np.abs(self.response), 1e-300)
        return 20.0 * np.log10(1.0 + rel)

    def select(self, mask: np.ndarray) -> 'FrequencyResponse':
        """Return a copy restricted to the frequencies where ``mask`` is true."""
        mask = np.asarray(mask, dtype=bool)
        return FrequencyResponse(
            self.freq_hz[mask], self.response[..., mask], list(self.inputs), list(self.outputs),
            None if self.noise_variance is None else self.noise_variance[..., mask],
            None if self.total_variance is None else self.total_variance[..., mask],
            dict(self.meta))

    # --- serialisation -------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """
        Return a JSON-ready dict.

        Keys: inputs, outputs, freq_hz, re, im [, noise_variance, total_variance].
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
        resp = np.asarray(d['re'], dtype=float) + 1j * np.asarray(d['im'], dtype=float)
        return cls(
            np.asarray(d['freq_hz'], dtype=float), resp, list(d.get('inputs', [])),
            list(d.get('outputs', [])),
            None if d.get('noise_variance') is None else np.asarray(d['noise_variance']),
            None if d.get('total_variance') is None else np.asarray(d['total_variance']),
            dict(d.get('meta', {})))

    def to_control(self):
        """Convert to ``control.FrequencyResponseData`` (needs the python-control package)."""
        import control  # optional dependency, imported lazily
        return control.FrequencyResponseData(
            self.response, self.omega, inputs=list(self.inputs), outputs=list(self.outputs))

    @classmethod
    def from_control(cls, frd) -> 'FrequencyResponse':
        omega = np.asarray(frd.omega, dtype=float)
        resp = np.asarray(getattr(frd, 'frdata', None) if hasattr(frd, 'frdata') else frd.fresp,
                          dtype=complex)
        return cls(omega / (2 * np.pi), resp, list(frd.input_labels), list(frd.output_labels))
