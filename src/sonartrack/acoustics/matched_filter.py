"""Active sonar waveforms and their matched filters: LFM pulse compression and a CW Doppler filter bank.

Complex baseband at the carrier f_c, sampled at f_s: a real passband pressure p(t) is
Re{sqrt(2) x(t) exp(2 pi i f_c t)}, so |x|^2 is the mean-square pressure (a pulse of level RL has
|x|^2 = 10^(RL/10) uPa^2). The transmitted pulses, for 0 <= t < tau (unit amplitude):

    CW   s(t) = 1                                              (the carrier itself)
    LFM  s(t) = exp(2 pi i (-B/2 t + k t^2 / 2)),  k = B / tau  (an up-sweep from f_c - B/2 to f_c + B/2)

Matched filter (the correlation with the replica, Van Trees, Detection, Estimation and Modulation Theory
III, ch. 10; Burdic, Underwater Acoustic System Analysis, ch. 13), at delay d (the echo's leading edge):

    z(d) = sum_t x(d + t) conj(s(t))                      computed as IFFT( X(f) conj(S(f)) )

The cell statistic is y = |z|^2 (paper P1's square-law statistic). With noise of variance sigma^2 per
sample the output noise has variance sigma^2 E (E = sum |s|^2 = tau f_s); an echo of amplitude a peaks at
a E, so the output SNR is a^2 tau f_s / sigma^2 = (the input SNR in the pulse's band B) x tau B: the
processing gain of pulse compression is the time-bandwidth product. The compressed LFM is a sinc of width
1/B in delay (first sidelobes -13.3 dB). An echo Doppler-shifted by f_d compresses at the delay
d - f_d / k = d - f_d tau / B (range-Doppler coupling of the LFM: the echo looks like the replica shifted in
time, Rihaczek, Principles of High-Resolution Radar, ch. 6); :func:`lfm_coupling_delay_s` gives the shift.

CW Doppler filter bank: replicas shifted to Doppler f_j (the DFT frequencies of a zero-padded window of the
pulse's length), z(d, f_j) = sum_t x(d + t) conj(s(t)) exp(-2 pi i f_j t / f_s): for the CW (s = 1) this is
the DFT of each window x(d .. d + tau), evaluated on delays d every ``hop`` samples, and only at the filters kept
(|f_j| <= the largest Doppler: 61 of the 400 bins at the defaults): where ``hop`` divides the pulse's L samples
each block of ``hop`` samples is transformed once and a window's DFT is the sum of its L / hop blocks' DFTs, block
b shifted by exp(-2 pi i f_j b hop / f_s) (measured: 60 -> 9 ms a ping of 61 beams); else one product of the
windows with the kept DFT rows. An echo at Doppler f_d
peaks in the filter nearest f_d (resolution ~ 0.88 / tau, paper P1's Doppler cell), at its delay. A tapered
replica s(t) = w(t) (Hann, w = 1 - cos(2 pi (t + 1/2) / L), mean 1) lowers the filters' sidelobes from -13.3 dB
(falling 6 dB an octave) to -31.5 dB (falling 18 dB an octave) at a wider main lobe (first null 2 / tau, not
1 / tau) and a loss in white noise of 10 log10(E[w^2]) = 10 log10(1.5) = 1.76 dB (Harris, Proc. IEEE 66(1), 1978,
table 1): the strong reverberation ridge of a moving platform then leaks into far fewer Doppler cells.
Doppler f_d <-> bistatic range rate (rate of the total path Tx -> target -> Rx): f_d = -f_c rdot_B / c.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require

#: the waveform kinds
WAVEFORMS = ("lfm", "cw")


@dataclass(frozen=True, slots=True)
class Waveform:
    """A transmitted pulse: ``kind`` (lfm or cw), length ``duration_s`` (s), carrier ``carrier_hz`` (Hz) and,
    for an LFM, its swept band ``bandwidth_hz`` (Hz, centred on the carrier; ignored for a CW)."""

    kind: str
    duration_s: float
    carrier_hz: float
    bandwidth_hz: float = 0.0

    def __post_init__(self):
        require(self.kind in WAVEFORMS, f"unknown waveform '{self.kind}': choose lfm or cw")
        require(self.duration_s > 0, f"the pulse length must be positive, got {self.duration_s:g} s")
        require(self.carrier_hz > 0, f"the carrier frequency must be positive, got {self.carrier_hz:g} Hz")
        require(self.kind != "lfm" or self.bandwidth_hz > 0,
                "an LFM pulse needs a positive bandwidth_hz (a zero-bandwidth LFM is a CW: set kind = 'cw')")

    @property
    def band_hz(self) -> float:
        """Width of the pulse's band: B for an LFM, the CW resolution ~ 1 / tau for a CW."""
        return self.bandwidth_hz if self.kind == "lfm" else 1.0 / self.duration_s

    @property
    def measures_doppler(self) -> bool:
        """Whether the matched filter resolves Doppler (a CW does; an LFM is Doppler tolerant)."""
        return self.kind == "cw"

    def n_samples(self, fs_hz: float) -> int:
        """Samples of the pulse at ``fs_hz``.

        Parameters
        ----------
        fs_hz : float
            Sample rate (Hz).

        Returns
        -------
        int
            round(duration_s fs_hz), at least 1.
        """
        return max(int(round(self.duration_s * fs_hz)), 1)

    def replica(self, fs_hz: float, doppler_hz: float = 0.0) -> np.ndarray:
        """Baseband samples s(t) exp(2 pi i f_d t) of the pulse (module doc), complex128 (L,).

        Parameters
        ----------
        fs_hz : float
            Sample rate (Hz).
        doppler_hz : float
            Doppler shift f_d (Hz).

        Returns
        -------
        ndarray, complex128, shape (L,)
            Unit-modulus samples (an LFM sweeps -B/2..+B/2 over the pulse).
        """
        t = np.arange(self.n_samples(fs_hz)) / fs_hz
        phase = 2.0 * np.pi * doppler_hz * t
        if self.kind == "lfm":
            k = self.bandwidth_hz / self.duration_s
            phase = phase + 2.0 * np.pi * (-0.5 * self.bandwidth_hz * t + 0.5 * k * t * t)
        return np.exp(1j * phase)


def lfm_coupling_delay_s(doppler_hz, waveform: Waveform):
    """Delay shift of the compressed peak of an LFM echo: -f_d tau / B (module doc).

    Parameters
    ----------
    doppler_hz : float or array_like
        Doppler shift f_d of the echo (Hz).
    waveform : Waveform
        An LFM pulse (length tau s, band B Hz).

    Returns
    -------
    float or ndarray
        Peak delay minus travel time (s); negative for a closing (up-shifted) echo of an up-sweep.
    """
    require(waveform.kind == "lfm", "range-Doppler coupling is the LFM's: a CW has none")
    return -np.asarray(doppler_hz, dtype=float) * waveform.duration_s / waveform.bandwidth_hz


def doppler_to_range_rate(doppler_hz, carrier_hz: float, sound_speed_mps: float):
    """Bistatic range rate of a Doppler shift: rdot_B = -c f_d / f_c.

    Parameters
    ----------
    doppler_hz : float or array_like
        Doppler shift f_d (Hz).
    carrier_hz, sound_speed_mps : float
        Carrier f_c (Hz) and sound speed c (m/s).

    Returns
    -------
    float or ndarray
        Rate of the total path Tx -> target -> Rx (m/s, positive opening).
    """
    return -np.asarray(doppler_hz, dtype=float) * sound_speed_mps / carrier_hz


def range_rate_to_doppler(range_rate_mps, carrier_hz: float, sound_speed_mps: float):
    """Doppler shift of a bistatic range rate: f_d = -f_c rdot_B / c.

    Parameters
    ----------
    range_rate_mps : float or array_like
        Rate of the total path (m/s, positive opening).
    carrier_hz, sound_speed_mps : float
        Carrier f_c (Hz) and sound speed c (m/s).

    Returns
    -------
    float or ndarray
        Doppler shift (Hz; positive for a closing target).
    """
    return -np.asarray(range_rate_mps, dtype=float) * carrier_hz / sound_speed_mps


def fft_length(n: int) -> int:
    """A fast FFT length >= n (5-smooth).

    Parameters
    ----------
    n : int
        Smallest length.

    Returns
    -------
    int
        scipy.fft.next_fast_len(n).
    """
    from scipy.fft import next_fast_len

    return int(next_fast_len(int(n)))


def pulse_compress(spectra: np.ndarray, replica: np.ndarray, n_delays: int) -> np.ndarray:
    """Matched-filter outputs z(d) (..., n_delays) from spectra (..., F) of zero-padded FFT length F.

    Parameters
    ----------
    spectra : ndarray (..., F)
        FFTs of the received series (beams or channels), each zero-padded to F >= samples + len(replica).
    replica : ndarray (L,)
        The pulse's baseband samples (:meth:`Waveform.replica`).
    n_delays : int
        Delays kept, d = 0 .. n_delays - 1 samples.

    Returns
    -------
    ndarray (..., n_delays), complex64
        z(d) = sum_t x(d + t) conj(s(t)) (module doc).
    """
    n_fft = spectra.shape[-1]
    require(replica.size <= n_fft, "the replica is longer than the FFT: zero-pad the series further")
    s_conj = np.conj(np.fft.fft(replica, n_fft)).astype(np.complex64)
    return np.fft.ifft(spectra * s_conj, axis=-1)[..., :n_delays].astype(np.complex64)


def cw_taper(n: int, taper: str) -> np.ndarray | None:
    """The CW replica's amplitude taper w (module doc), mean 1, float32; None for the rectangular pulse.

    Parameters
    ----------
    n : int
        Samples of the pulse.
    taper : str
        rect or hann.

    Returns
    -------
    numpy.ndarray or None
        (n,) w(t) = 1 - cos(2 pi (t + 1/2) / n) for hann (symmetric, nonzero at both ends), None for rect.
    """
    require(taper in ("rect", "hann"), f"unknown CW taper '{taper}': choose rect or hann")
    if taper == "rect":
        return None
    return (1.0 - np.cos(2.0 * np.pi * (np.arange(n) + 0.5) / n)).astype(np.float32)


def cw_doppler_bank(series: np.ndarray, fs_hz: float, waveform: Waveform, max_doppler_hz: float,
                    hop: int, pad: int = 2, taper: str = "rect") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The CW matched filter at every Doppler of the bank, on delays every ``hop`` samples (module doc).

    Parameters
    ----------
    series : ndarray (..., M)
        Received baseband series (beams), complex.
    fs_hz : float
        Sample rate (Hz).
    waveform : Waveform
        A CW pulse of L = tau f_s samples.
    max_doppler_hz : float
        The bank spans Doppler shifts |f_d| <= this (Hz).
    hop : int
        Delay step of the output (samples).
    pad : int
        Zero-padding factor of each window's DFT: filters 1 / (pad tau) apart.
    taper : str
        The replica's amplitude taper (:func:`cw_taper`): rect or hann.

    Returns
    -------
    z : ndarray (..., D, J), complex64
        Outputs at delays d = 0, hop, 2 hop, ... (windows inside the series) and Doppler filters f_j.
    delay_s : ndarray (D,)
        Delays of the rows (s).
    doppler_hz : ndarray (J,)
        Doppler of the filters (Hz), increasing.
    """
    require(waveform.kind == "cw", "the Doppler filter bank here is the CW's")
    n = waveform.n_samples(fs_hz)
    m = series.shape[-1]
    require(m >= n, f"the series ({m} samples) is shorter than the pulse ({n} samples)")
    n_fft = fft_length(pad * n)
    f = np.fft.fftfreq(n_fft, 1.0 / fs_hz)
    f = np.sort(f[np.abs(f) <= max_doppler_hz])
    n_delays = (m - n) // hop + 1
    w = cw_taper(n, taper)
    # the kept filters' DFT rows exp(-2 pi i f_j t / f_s) (the zero-padded FFT's bins f_j, only those kept)
    rows = np.exp(-2j * np.pi * np.outer(np.arange(n), f) / fs_hz) * (1.0 if w is None else w[:, None])
    x = np.asarray(series, np.complex64)
    if w is None and n % hop == 0:
        z = _block_bank(x, rows[:hop].astype(np.complex64), n // hop, n_delays, hop, f / fs_hz)
    else:
        windows = np.lib.stride_tricks.sliding_window_view(x, n, axis=-1)[..., ::hop, :][..., :n_delays, :]
        z = (np.ascontiguousarray(windows).reshape(-1, n) @ rows.astype(np.complex64)).reshape(windows.shape[:-1]
                                                                                               + (f.size,))
    return z, np.arange(n_delays) * hop / fs_hz, f


def _block_bank(x: np.ndarray, rows: np.ndarray, n_blocks: int, n_delays: int, hop: int,
                cycles_per_sample) -> np.ndarray:
    """The CW bank on windows of ``n_blocks`` blocks of ``hop`` samples: each block's DFT Y(b, f) once, then
    z(d_k, f) = sum_b exp(-2 pi i f b hop / f_s) Y(k + b, f) (the window starting at block k; the same sums as
    each window's DFT, n_blocks times less work)."""
    blocks = x[..., :(n_delays + n_blocks - 1) * hop].reshape(x.shape[:-1] + (n_delays + n_blocks - 1, hop))
    y = (blocks.reshape(-1, hop) @ rows).reshape(blocks.shape[:-1] + (rows.shape[1],))
    shift = np.exp(-2j * np.pi * hop * np.asarray(cycles_per_sample)).astype(np.complex64)
    z = y[..., n_blocks - 1: n_blocks - 1 + n_delays, :].copy()
    for b in range(n_blocks - 2, -1, -1):  # Horner: z = Y_k + shift (Y_k+1 + shift (...))
        z *= shift
        z += y[..., b: b + n_delays, :]
    return z
