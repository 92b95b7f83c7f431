//! Welch spectrum of a channel: the broad spectral peak a resonance leaves in it, and the lines
//! (tones) it shows, their frequencies measured to the runs' resolution.
//!
//! A resonance (a narrow-band random vibration, `noise::Resonance`) shows in the power spectral
//! density as a peak several resolutions wide above a smooth background; a sinusoid shows as a line
//! (the window's main lobe, about two resolutions); the white, flicker and random-walk terms are
//! smooth power laws. diagnose offers a resonance only where such a peak stands out, searches its
//! frequency and bandwidth around the peak's (`candidates::resonance_grid`) and keeps the bandwidth
//! within 0.15-3 times the peak's width.

use crate::stats::median;

/// A broad peak of the spectrum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectralPeak {
    /// Centre (excess-power weighted mean over the half-power region), Hz.
    pub frequency_hz: f64,
    /// Half-power (-3 dB) full width, corrected for the window's resolution, Hz.
    pub bandwidth_hz: f64,
    /// Peak power over the background (smoothed over three bins).
    pub ratio: f64,
    /// The raised region around it (the smoothed ratio above about 3 sigma of the background), Hz:
    /// the spectrum has no line there, so a sinusoid is not offered inside it.
    pub lo_hz: f64,
    pub hi_hz: f64,
}

impl SpectralPeak {
    /// Whether `f_hz` lies inside the peak's raised region.
    pub fn covers(&self, f_hz: f64) -> bool {
        (self.lo_hz..=self.hi_hz).contains(&f_hz)
    }
}

/// Welch periodogram: segments of `seg` samples (a power of two), Hann window, each segment's mean
/// removed, no overlap; the mean of |X_k|^2 over the segments for k = 0..seg/2 (unnormalised: only
/// ratios are used). Returns the powers and the number of segments.
pub fn welch(x: &[f64], seg: usize) -> (Vec<f64>, usize) {
    welch_runs(&[x], seg)
}

/// [`welch`] over the segments of several runs of one sensor together (each run cut on its own).
pub fn welch_runs(xs: &[&[f64]], seg: usize) -> (Vec<f64>, usize) {
    let window = hann(seg);
    let mut p = vec![0.0; seg / 2 + 1];
    let (mut re, mut im) = (vec![0.0; seg], vec![0.0; seg]);
    let mut k = 0;
    for x in xs {
        for part in x.chunks_exact(seg) {
            let mean = stats::mean(part);
            for i in 0..seg {
                re[i] = (part[i] - mean) * window[i];
                im[i] = 0.0;
            }
            noise::fft::fft(&mut re, &mut im);
            for (i, pi) in p.iter_mut().enumerate() {
                *pi += re[i] * re[i] + im[i] * im[i];
            }
            k += 1;
        }
    }
    p.iter_mut().for_each(|v| *v /= k.max(1) as f64);
    (p, k)
}

/// The Hann window of `seg` samples (periodic form).
fn hann(seg: usize) -> Vec<f64> {
    (0..seg)
        .map(|n| 0.5 - 0.5 * (std::f64::consts::TAU * n as f64 / seg as f64).cos())
        .collect()
}

/// The Welch segment length of the spectra here: 4096 samples, or a sixteenth of the shortest run
/// if shorter. `Fft::Peak`: a power of two, half the next one above a sixteenth (the broad peak's);
/// `Fft::Line`: the largest power of two up to a sixteenth (the lines', so that they are sought
/// with the resolution of the line checks whenever a sixteenth is a power of two);
/// `Fft::No`: any length (direct DFTs).
fn segment_length(xs: &[&[f64]], fft: Fft) -> usize {
    let n = xs.iter().map(|x| x.len()).min().unwrap_or(0);
    match fft {
        Fft::Peak => 4096usize.min((n / 16).next_power_of_two() / 2).max(1),
        Fft::Line => 4096usize.min(1 << (n / 16).max(1).ilog2()),
        Fft::No => 4096.min(n / 16),
    }
}

/// How a spectrum's segment length is chosen ([`segment_length`]).
#[derive(Clone, Copy)]
enum Fft {
    Peak,
    Line,
    No,
}

/// The strongest broad peak of `x`'s spectrum, if one stands out. Welch spectrum with segments of
/// 4096 samples (a sixteenth of the log if shorter, a power of two, at least 256). Background at bin
/// k: the median of 61 bins log-spaced over [k/2, 2 k] (symmetric in log frequency, so a power law
/// is its own median), taken again without the bins the first pass found raised. A peak is a
/// maximum of the 3-bin-smoothed ratio to the background that exceeds both 1.2 and 1 + 6/sqrt(3 K) (K segments: each Welch bin has relative spread 1/sqrt(K), so 6 sigma
/// of a 3-bin mean, about 1e-9 one-sided per bin), whose excess power stays above half its top over at
/// least 4 resolutions (a Hann-windowed line is about 2 wide: lines are left to the sinusoid), between
/// 6 resolutions and 0.45 times the sample rate. Of the peaks found (up to 8, each masked before the
/// next is sought), the one with the largest excess power.
pub fn broad_peak(x: &[f64], dt_s: f64) -> Option<SpectralPeak> {
    broad_peak_runs(&[x], dt_s)
}

/// [`broad_peak`] of the Welch spectrum over several runs' segments together.
pub fn broad_peak_runs(xs: &[&[f64]], dt_s: f64) -> Option<SpectralPeak> {
    let seg = segment_length(xs, Fft::Peak);
    if seg < 256 {
        return None;
    }
    let (p, k) = welch_runs(xs, seg);
    let df = 1.0 / (seg as f64 * dt_s);
    let nb = p.len();
    let spectrum = Spectrum::new(p, k);
    let lo = 6usize;
    let hi = ((0.45 / dt_s) / df).floor() as usize;
    if hi <= lo + 2 || hi + 1 >= nb {
        return None;
    }
    let threshold = 1.2f64.max(1.0 + 6.0 / (3.0 * k as f64).sqrt());
    let mut masked = vec![false; nb];
    let mut best: Option<(f64, SpectralPeak)> = None;
    for _ in 0..8 {
        let Some(top) = (lo..=hi)
            .filter(|&i| !masked[i])
            .max_by(|&a, &b| spectrum.ratio(a).total_cmp(&spectrum.ratio(b)))
        else {
            break;
        };
        let r_top = spectrum.ratio(top);
        if r_top < threshold {
            break;
        }
        let region = spectrum.region(top, (lo, hi), threshold);
        for m in masked
            .iter_mut()
            .take((region.b2 + 2).min(nb - 1) + 1)
            .skip(region.a2.saturating_sub(2))
        {
            *m = true;
        }
        if let Some((power, peak)) = spectrum.peak(&region, r_top, df) {
            if best.as_ref().is_none_or(|(pw, _)| power > *pw) {
                best = Some((power, peak));
            }
        }
    }
    best.map(|(_, p)| p)
}

/// Power of the runs `xs` near frequency `f0_hz`, Welch-averaged over segments of `seg` samples (Hann
/// window), at f0 + j df for j = -span..=span, df = 1 / (seg dt). Each value is a direct DFT at that
/// frequency (Goertzel-style rotation), so f0 need not lie on a bin. The frequencies go through the
/// log [`FREQ_LANES`] at a time ([`rotation_sums`]), each by its own operations.
fn local_spectrum(xs: &[&[f64]], dt_s: f64, f0_hz: f64, seg: usize, span: i32) -> Vec<f64> {
    let k: usize = xs.iter().map(|x| x.len() / seg).sum();
    let df = 1.0 / (seg as f64 * dt_s);
    let window = hann(seg);
    let js: Vec<i32> = (-span..=span).collect();
    let mut out = Vec::with_capacity(js.len());
    for group in js.chunks(FREQ_LANES) {
        // Spare lanes repeat the first frequency; their sums are dropped.
        let rot: [(f64, f64); FREQ_LANES] = std::array::from_fn(|l| {
            let j = group.get(l).copied().unwrap_or(group[0]);
            let w = std::f64::consts::TAU * (f0_hz + f64::from(j) * df) * dt_s;
            (w.cos(), w.sin())
        });
        let totals = rotation_sums(xs, &window, rot);
        out.extend(totals[..group.len()].iter().map(|t| t / k.max(1) as f64));
    }
    out
}

/// Frequencies per pass of [`rotation_sums`].
const FREQ_LANES: usize = 8;

allan::wide_variant! {
    /// For each lane's rotation (cos w, sin w): the sum over the runs' segments (in order) of
    /// |sum_n (x_n - mean) window_n e^{-i w n}|^2, the rotation advanced by angle addition, in each
    /// lane the operations of that frequency alone (the same bits); the windowed sample is the same
    /// in every lane, so it is formed once.
    fn rotation_sums(
        xs: &[&[f64]],
        window: &[f64],
        rot: [(f64, f64); FREQ_LANES]
    ) -> [f64; FREQ_LANES] {
        let seg = window.len();
        let (c1, s1): ([f64; FREQ_LANES], [f64; FREQ_LANES]) =
            (rot.map(|r| r.0), rot.map(|r| r.1));
        let mut total = [0.0; FREQ_LANES];
        for seg_x in xs.iter().flat_map(|x| x.chunks_exact(seg)) {
            let mean = stats::mean(seg_x);
            let (mut re, mut im) = ([0.0; FREQ_LANES], [0.0; FREQ_LANES]);
            let (mut c, mut sn) = ([1.0; FREQ_LANES], [0.0; FREQ_LANES]);
            for (v, wn) in seg_x.iter().zip(window) {
                let a = (v - mean) * wn;
                for l in 0..FREQ_LANES {
                    re[l] += a * c[l];
                    im[l] -= a * sn[l];
                    let c2 = c[l] * c1[l] - sn[l] * s1[l];
                    sn[l] = sn[l] * c1[l] + c[l] * s1[l];
                    c[l] = c2;
                }
            }
            for l in 0..FREQ_LANES {
                total[l] += re[l] * re[l] + im[l] * im[l];
            }
        }
        total
    }
}

/// May a sinusoid at `f0_hz` be named in the runs `xs`: there is a spectral line there
/// ([`is_spectral_line_runs`]),
/// or the spectrum cannot tell (the frequency below 6 resolutions of the Welch segments, at or
/// above the Nyquist frequency, or the log too short for segments).
pub fn line_allowed_runs(xs: &[&[f64]], dt_s: f64, f0_hz: f64) -> bool {
    let seg = segment_length(xs, Fft::No);
    if seg < 64 || f0_hz.is_nan() || f0_hz <= 0.0 || f0_hz >= 0.5 / dt_s {
        return true;
    }
    f0_hz < 6.0 / (seg as f64 * dt_s) || is_spectral_line_runs(xs, dt_s, f0_hz)
}

/// Is there a spectral line (a sinusoid) at `f0_hz` in the runs `xs`? A Welch spectrum (segments
/// of 4096 samples, or a sixteenth of the shortest run if shorter, Hann window) must, at f0, exceed the median of the
/// bins 6 to 20 resolutions away by a factor above both 2 and 1 + 6/sqrt(K) (K segments: the
/// relative spread of a K-segment average is 1/sqrt(K), so 6 sigma), and fall to a quarter of its
/// peak 4 resolutions away (a Hann-windowed line leaks over +-2 bins; a broad narrow-band process
/// does not fall off). Used to tell a physical tone from a sinusoid fitted as a stand-in. Of
/// several runs, the runs' spectrum or any run's own (a tone whose frequency moves from run to run
/// is a line in each run, not in their spectrum; see [`spectral_lines_runs`]).
pub fn is_spectral_line_runs(xs: &[&[f64]], dt_s: f64, f0_hz: f64) -> bool {
    is_line_in(xs, dt_s, f0_hz)
        || (xs.len() > 1 && xs.iter().any(|x| is_line_in(&[x], dt_s, f0_hz)))
}

/// The test of [`is_spectral_line_runs`] on the spectrum of `xs` (one spectrum over all of them).
fn is_line_in(xs: &[&[f64]], dt_s: f64, f0_hz: f64) -> bool {
    let seg = segment_length(xs, Fft::No);
    if seg < 64 || f0_hz.is_nan() || f0_hz <= 0.0 || f0_hz >= 0.5 / dt_s {
        return false;
    }
    let df = 1.0 / (seg as f64 * dt_s);
    if f0_hz < 6.0 * df {
        return false;
    }
    let k = xs.iter().map(|x| x.len() / seg).sum::<usize>() as f64;
    let span = 20;
    let p = local_spectrum(xs, dt_s, f0_hz, seg, span);
    let at = |j: i32| p[(j + span) as usize];
    let peak = (-1..=1).map(at).fold(0.0, f64::max);
    let mut side: Vec<f64> = (6..=span).flat_map(|j| [at(j), at(-j)]).collect();
    let background = median(&mut side);
    let far = at(4).max(at(-4));
    background > 0.0 && peak > background * 2f64.max(1.0 + 6.0 / k.sqrt()) && far < 0.25 * peak
}

/// Most lines [`spectral_lines_runs`] gives (the strongest).
pub const MAX_LINES: usize = 8;

/// The frequency resolution of the Welch spectrum [`spectral_lines_runs`] finds lines in (None
/// when the runs are too short for one: a sixteenth of the shortest under 64 samples): below 6
/// resolutions the spectrum cannot tell a line.
pub fn line_resolution_hz(xs: &[&[f64]], dt_s: f64) -> Option<f64> {
    let seg = segment_length(xs, Fft::Line);
    (seg >= 64).then(|| 1.0 / (seg as f64 * dt_s))
}

/// The lines (sinusoids) the Welch spectrum of the runs `xs` shows, strongest first (at most
/// [`MAX_LINES`]), Hz. Sought in segments of 4096 samples (the largest power of two up to a
/// sixteenth of the shortest run if shorter), Hann window ([`coarse_lines`]), in the runs' spectrum
/// and, for several runs, in each run's own (a tone whose frequency moves from run to run leaves
/// several lines a resolution or two apart in the runs' spectrum, which then falls off too slowly
/// to pass for one line; each run's shows its own). Each is then measured on the runs' longest
/// segments ([`refine_lines`]).
pub fn spectral_lines_runs(xs: &[&[f64]], dt_s: f64) -> Vec<f64> {
    let seg = segment_length(xs, Fft::Line);
    if seg < 64 {
        return Vec::new();
    }
    let mut coarse = coarse_lines(xs, seg, dt_s);
    if xs.len() > 1 {
        for x in xs {
            coarse.extend(coarse_lines(&[x], seg, dt_s));
        }
    }
    refine_lines(xs, dt_s, &coarse, 1.0 / (seg as f64 * dt_s))
}

/// The lines of the Welch spectrum of `xs` with segments of `seg` samples, Hz, strongest first
/// (the strongest [`MAX_LINES`]). A line is a local maximum between 6 resolutions and the Nyquist
/// frequency that passes the test of [`is_spectral_line_runs`] on the FFT bins: above the median of
/// the bins 6 to 20 resolutions away by a factor above both 2 and 1 + 6/sqrt(K) (6 sigma of a
/// K-segment average), and down to a quarter of its peak 4 resolutions away (a Hann-windowed line's
/// main lobe is 4 bins wide; a broad peak does not fall off). Its frequency is interpolated between
/// bins ([`gaussian_vertex`]).
fn coarse_lines(xs: &[&[f64]], seg: usize, dt_s: f64) -> Vec<f64> {
    let (p, k) = welch_runs(xs, seg);
    let df = 1.0 / (seg as f64 * dt_s);
    let span: isize = 20;
    let threshold = 2f64.max(1.0 + 6.0 / (k as f64).sqrt());
    let nb = p.len();
    // The spectrum of a real series is even about 0 and about the Nyquist frequency: bins beyond
    // either end are their mirror images.
    let at = |i: usize, j: isize| {
        let b = (i as isize + j).unsigned_abs();
        p[if b >= nb { 2 * (nb - 1) - b } else { b }]
    };
    let mut found: Vec<(f64, f64)> = Vec::new();
    for i in 6..nb - 1 {
        if !(p[i] > 0.0 && p[i] >= p[i - 1] && p[i] >= p[i + 1]) {
            continue;
        }
        // The line's frequency and power at it (the parabola's vertex): a line between two bins
        // loses up to 1.4 dB in either (the Hann window's scalloping).
        let (shift, top) = gaussian_vertex(p[i - 1], p[i], p[i + 1]);
        let j0 = (i as f64 + shift).round() as usize;
        let mut side: Vec<f64> = (6..=span).flat_map(|j| [at(j0, j), at(j0, -j)]).collect();
        let background = median(&mut side);
        let far = at(j0, 4).max(at(j0, -4));
        if background > 0.0 && top > background * threshold && far < 0.25 * top {
            found.push(((i as f64 + shift) * df, top / background));
        }
    }
    found.sort_by(|a, b| b.1.total_cmp(&a.1));
    found.truncate(MAX_LINES);
    found.into_iter().map(|f| f.0).collect()
}

/// The vertex of the parabola through the log powers `a`, `b`, `c` of three adjacent bins, the
/// middle one the highest (Gaussian interpolation, Gasior & Gonzalez 2004, CERN AB-Note-2004-021):
/// the offset from the middle bin, within +-0.5 bin, and the power there. For a Hann-windowed tone
/// its bias is at most 0.016 bin (checked in the tests here). No curvature: the middle bin.
fn gaussian_vertex(a: f64, b: f64, c: f64) -> (f64, f64) {
    let (a, lb, c) = (a.ln(), b.ln(), c.ln());
    let curvature = a - 2.0 * lb + c;
    if curvature < 0.0 {
        let d = (0.5 * (a - c) / curvature).clamp(-0.5, 0.5);
        (d, (lb - 0.25 * (a - c) * d).exp())
    } else {
        (0.0, b)
    }
}

/// Longest Welch segment the line frequencies are measured on (2^18 samples: 2621 s, a
/// resolution of 0.00038 Hz at 100 Hz).
const FINE_SEGMENT_MAX: usize = 1 << 18;

/// The Welch segment of [`refine_lines`]: the largest power of two up to the shortest run, at most
/// [`FINE_SEGMENT_MAX`].
fn fine_segment_length(xs: &[&[f64]]) -> usize {
    let n = xs.iter().map(|x| x.len()).min().unwrap_or(0).max(1);
    FINE_SEGMENT_MAX.min(1 << n.ilog2())
}

/// The resolution the line frequencies of [`spectral_lines_runs`] are measured to, Hz (None when
/// the runs are too short for lines): a line's frequency is known to half of it.
pub fn line_frequency_resolution_hz(xs: &[&[f64]], dt_s: f64) -> Option<f64> {
    line_resolution_hz(xs, dt_s)?;
    Some(1.0 / (fine_segment_length(xs) as f64 * dt_s))
}

/// Each line found at `coarse` (Hz, on segments of resolution `df_coarse`) measured on the runs'
/// longest segments: the Welch spectrum of segments of [`fine_segment_length`] (2^18 samples, or
/// the largest power of two up to the shortest run: 64 times finer than the search's at 100 Hz,
/// 16 times at least), the mean of every run's periodograms, Hann window; its highest bin within
/// one coarse resolution of the line, refined by [`gaussian_vertex`]. The maximum of the
/// periodogram is the maximum-likelihood frequency of one tone in white noise (Rife & Boorstyn
/// 1974, IEEE Trans. Inf. Theory 20(5)), the noise near a line being locally white; averaging the
/// runs' periodograms (Welch 1967) keeps it where the runs share the tone. Resolution 1/(L dt) for
/// segments of L samples; bias at most 0.016 of it (the interpolation's, for a Hann window) plus
/// the noise's, a small fraction of a bin for any line the search finds (its excess over the
/// background grows with the segment: 64 times at 2^18 against 4096). Strongest first, by the
/// peak's ratio to the median of the fine bins within 20 coarse resolutions; a line within two
/// coarse resolutions of a stronger one (inside the search's main lobe, where it could not be told
/// from it) is the same tone, at another frequency in another run (or the same line found twice),
/// and is dropped: where the runs hold the tone at different frequencies, it is the strongest's.
fn refine_lines(xs: &[&[f64]], dt_s: f64, coarse: &[f64], df_coarse: f64) -> Vec<f64> {
    let seg = fine_segment_length(xs);
    if coarse.is_empty() || (seg as f64 * dt_s) * df_coarse <= 1.0 {
        let mut out = coarse.to_vec();
        out.truncate(MAX_LINES);
        return out;
    }
    let (p, _) = welch_runs(xs, seg);
    let df = 1.0 / (seg as f64 * dt_s);
    let nb = p.len();
    let bin = |f: f64| ((f / df).round().max(1.0) as usize).min(nb - 2);
    let mut fine: Vec<(f64, f64)> = Vec::new();
    for &f in coarse {
        let (lo, hi) = (bin(f - df_coarse), bin(f + df_coarse));
        let Some(i) = (lo..=hi).max_by(|&a, &b| p[a].total_cmp(&p[b])) else {
            continue;
        };
        if !(p[i - 1] > 0.0 && p[i] > 0.0 && p[i + 1] > 0.0) {
            continue;
        }
        let mut near = p[bin(f - 20.0 * df_coarse)..=bin(f + 20.0 * df_coarse)].to_vec();
        let background = median(&mut near);
        let shift = gaussian_vertex(p[i - 1], p[i], p[i + 1]).0;
        fine.push(((i as f64 + shift) * df, p[i] / background));
    }
    fine.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut out: Vec<f64> = Vec::new();
    for (f, _) in fine {
        if out.iter().all(|g| (g - f).abs() > 2.0 * df_coarse) {
            out.push(f);
        }
    }
    out.truncate(MAX_LINES);
    out
}

/// The broad peak and the lines of the runs `xs` ([`broad_peak_runs`], [`spectral_lines_runs`]),
/// without a broad peak that is only a line: a strong tone halfway between two bins of the
/// peak's spectrum is, after the 3-bin smoothing, 4 bins wide at half power, as wide as the
/// narrowest peak. A peak is that line when the lines inside its raised region hold at least half
/// of the region's excess power in the runs' fine spectrum (the spectrum [`refine_lines`] measures
/// the lines on, where a line keeps its power within its main lobe, +-2 fine bins, and a
/// resonance spreads its own over its bandwidth, many fine bins): each line's excess over its main
/// lobe +-3 fine bins, against the excess summed over the region, both over the median of the fine
/// bins within 20 coarse resolutions of the peak.
pub fn peak_and_lines_runs(xs: &[&[f64]], dt_s: f64) -> (Option<SpectralPeak>, Vec<f64>) {
    let lines = spectral_lines_runs(xs, dt_s);
    let peak = broad_peak_runs(xs, dt_s);
    let inside: Vec<f64> = lines
        .iter()
        .copied()
        .filter(|&f| peak.is_some_and(|p| p.covers(f)))
        .collect();
    let peak = match peak {
        Some(p) if !inside.is_empty() && lines_hold_peak(xs, dt_s, &p, &inside) => None,
        other => other,
    };
    (peak, lines)
}

/// Whether the lines `inside` the broad peak `peak` hold at least half its excess power in the
/// fine spectrum ([`peak_and_lines_runs`]).
fn lines_hold_peak(xs: &[&[f64]], dt_s: f64, peak: &SpectralPeak, inside: &[f64]) -> bool {
    let Some(df_coarse) = line_resolution_hz(xs, dt_s) else {
        return false;
    };
    let seg = fine_segment_length(xs);
    let df = 1.0 / (seg as f64 * dt_s);
    if df >= df_coarse {
        return false;
    }
    let (p, _) = welch_runs(xs, seg);
    let nb = p.len();
    let bin = |f: f64| ((f / df).round().max(1.0) as usize).min(nb - 2);
    let centre = 0.5 * (peak.lo_hz + peak.hi_hz);
    let mut near = p[bin(centre - 20.0 * df_coarse)..=bin(centre + 20.0 * df_coarse)].to_vec();
    let background = median(&mut near);
    let excess =
        |a: usize, b: usize| -> f64 { (a..=b).map(|i| (p[i] - background).max(0.0)).sum() };
    let total = excess(bin(peak.lo_hz), bin(peak.hi_hz));
    let in_lines: f64 = inside
        .iter()
        .map(|&f| {
            let i = bin(f);
            excess(i.saturating_sub(3).max(1), (i + 3).min(nb - 1))
        })
        .sum();
    total > 0.0 && in_lines >= 0.5 * total
}

/// A Welch spectrum with its background.
struct Spectrum {
    p: Vec<f64>,
    bg: Vec<f64>,
}

/// The bins around a peak's top: its half-power region [a, b] and the whole raised region
/// [a2, b2].
struct Region {
    a: usize,
    b: usize,
    a2: usize,
    b2: usize,
}

impl Spectrum {
    /// Background: the median over a log-spaced window, twice; the second pass leaves out the bins
    /// the first found raised (a peak a few hertz wide would otherwise lift its own background).
    fn new(p: Vec<f64>, k: usize) -> Spectrum {
        let nb = p.len();
        let bg1 = background(&p, &vec![false; nb]);
        let flag = 1.0 + 3.0 / (3.0 * k as f64).sqrt();
        let raised: Vec<bool> = (0..nb)
            .map(|i| {
                i >= 2
                    && i + 1 < nb
                    && (i - 1..=i + 1).map(|b| p[b] / bg1[b]).sum::<f64>() / 3.0 > flag.max(1.1)
            })
            .collect();
        let bg = background(&p, &raised);
        Spectrum { p, bg }
    }

    /// The ratio of power to background at bin `i`, smoothed over three bins (0 where undefined).
    fn ratio(&self, i: usize) -> f64 {
        let r: f64 = (i - 1..=i + 1).map(|b| self.p[b] / self.bg[b]).sum::<f64>() / 3.0;
        if r.is_finite() {
            r
        } else {
            0.0
        }
    }

    /// The regions of the peak at bin `top` within [lo, hi]: where its excess power (3-bin
    /// smoothed) stays above half its top, and where the smoothed ratio stays above half the
    /// threshold's excess (about 3 sigma: a resonance's wings belong to it, and are masked with it
    /// rather than found as peaks of their own).
    fn region(&self, top: usize, (lo, hi): (usize, usize), threshold: f64) -> Region {
        let excess = |i: usize| (self.ratio(i) - 1.0) * self.bg[i];
        let half = 0.5 * excess(top);
        let mut a = top;
        while a > lo && excess(a - 1) > half {
            a -= 1;
        }
        let mut b = top;
        while b < hi && excess(b + 1) > half {
            b += 1;
        }
        let floor = 1.0 + 0.5 * (threshold - 1.0);
        let (mut a2, mut b2) = (a, b);
        while a2 > lo && self.ratio(a2 - 1) > floor {
            a2 -= 1;
        }
        while b2 < hi && self.ratio(b2 + 1) > floor {
            b2 += 1;
        }
        Region { a, b, a2, b2 }
    }

    /// The peak of `region` (top ratio `r_top`) with its excess power, unless it is a line (under
    /// 4 bins wide) or has no excess; bins are `df` wide.
    fn peak(&self, region: &Region, r_top: f64, df: f64) -> Option<(f64, SpectralPeak)> {
        let (p, bg) = (&self.p, &self.bg);
        let Region { a, b, a2, b2 } = *region;
        let width_bins = (b - a + 1) as f64;
        if width_bins < 4.0 {
            return None; // a line
        }
        let power: f64 = (a2..=b2).map(|i| (p[i] - bg[i]).max(0.0)).sum();
        let (mut w, mut wf) = (0.0, 0.0);
        for i in a..=b {
            let e = (p[i] - bg[i]).max(0.0);
            w += e;
            wf += e * i as f64;
        }
        if w <= 0.0 {
            return None;
        }
        // The smoothing (3 bins) and the Hann main lobe (3 dB width 1.44 bins) widen the peak.
        let width = (width_bins * width_bins - 1.44f64.powi(2) - 1.0)
            .max(1.0)
            .sqrt()
            * df;
        let peak = SpectralPeak {
            frequency_hz: wf / w * df,
            bandwidth_hz: width,
            ratio: r_top,
            lo_hz: a2 as f64 * df,
            hi_hz: b2 as f64 * df,
        };
        Some((power, peak))
    }
}

/// The median of `p` over 61 bins log-spaced over [i/2, 2 i] at every bin i >= 2, leaving out the
/// `raised` bins unless fewer than 15 remain (NaN below bin 2).
fn background(p: &[f64], raised: &[bool]) -> Vec<f64> {
    let nb = p.len();
    let window = |i: usize| -> Vec<usize> {
        (-30..=30)
            .map(|j| {
                let b = (i as f64 * 2f64.powf(f64::from(j) / 30.0)).round() as usize;
                b.clamp(1, nb - 1)
            })
            .collect()
    };
    (0..nb)
        .map(|i| {
            if i < 2 {
                return f64::NAN;
            }
            let all = window(i);
            let mut v: Vec<f64> = all.iter().filter(|&&b| !raised[b]).map(|&b| p[b]).collect();
            if v.len() < 15 {
                v = all.iter().map(|&b| p[b]).collect();
            }
            median(&mut v)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::normals;

    /// A flicker-like noise from the normals `g`: six Gauss-Markov processes of std 0.3 with time
    /// constants 1, 4, ..., 1024 s, each driven by `g` at its own lag.
    fn flicker_like(g: &[f64], dt: f64) -> Vec<f64> {
        let n = g.len();
        let mut gm = [0.0f64; 6];
        (0..n)
            .map(|k| {
                let mut flicker = 0.0;
                for (j, s) in gm.iter_mut().enumerate() {
                    let phi = (-dt / 4f64.powi(j as i32)).exp();
                    *s = phi * *s + (1.0 - phi * phi).sqrt() * 0.3 * g[(k + 7919 * j) % n];
                    flicker += *s;
                }
                flicker
            })
            .collect()
    }

    /// A resonance at `f0` Hz, `bw` Hz wide (AR(2) driven by 0.05 `e`, poles r e^{+-i theta}: a
    /// peak at f0 with -3 dB width -ln(r^2) / (2 pi dt)) in the white noise `w`.
    fn resonance_in(w: &[f64], e: &[f64], (f0, bw): (f64, f64), dt: f64) -> Vec<f64> {
        let r = (-std::f64::consts::PI * bw * dt).exp();
        let th = std::f64::consts::TAU * f0 * dt;
        let (mut y1, mut y2) = (0.0, 0.0);
        w.iter()
            .zip(e)
            .map(|(w, e)| {
                let y = 2.0 * r * th.cos() * y1 - r * r * y2 + 0.05 * e;
                y2 = y1;
                y1 = y;
                y + w
            })
            .collect()
    }

    /// A resonance (AR(2) with poles r e^{+-i theta}: a peak at f0 with -3 dB width
    /// -ln(r^2) / (2 pi dt) = 0.6 Hz) in white noise is found at its frequency and width; white
    /// noise, a random walk and a pure tone give no broad peak.
    #[test]
    fn broad_peaks_found_lines_and_power_laws_ignored() {
        let dt = 0.01;
        let n = 1 << 20;
        let w = normals(n, 2);
        let e = normals(n, 3);
        let (f0, bw) = (12.0, 0.6);
        let x = resonance_in(&w, &e, (f0, bw), dt);
        let p = broad_peak(&x, dt).expect("a resonance");
        // Two resolutions (100 Hz / 4096 = 0.024 Hz) on the frequency; the width from ~25 bins of
        // 256-segment averages (each bin's relative spread 1/16) within the 25 %.
        assert!((p.frequency_hz - f0).abs() < 0.05, "{p:?}");
        assert!((p.bandwidth_hz / bw - 1.0).abs() < 0.25, "{p:?}");
        assert_eq!(broad_peak(&w, dt), None);
        let mut acc = 0.0;
        let walk: Vec<f64> = w
            .iter()
            .map(|v| {
                acc += 0.01 * v;
                acc + v
            })
            .collect();
        assert_eq!(broad_peak(&walk, dt), None);
        let tone: Vec<f64> = (0..n)
            .map(|k| w[k] + 0.3 * (std::f64::consts::TAU * 7.3 * k as f64 * dt).sin())
            .collect();
        assert_eq!(broad_peak(&tone, dt), None);
    }

    /// A tone in white noise is found as a line at its frequency, to a fraction of the resolution
    /// (the Gaussian interpolation's bias for a Hann window is at most 0.016 bin; the noise adds
    /// about 0.01 bin at this SNR), in one run or pooled over runs; white noise, a random walk and
    /// a resonance (a broad peak) show no line.
    #[test]
    fn lines_found_at_their_frequency_and_nothing_else_is_a_line() {
        let dt = 0.01;
        let n = 1 << 18;
        let w = normals(n, 5);
        let resolution = 1.0 / (4096.0 * dt);
        for f0 in [0.5643, 3.21, 31.7] {
            let tone: Vec<f64> = (0..n)
                .map(|k| w[k] + 0.2 * (std::f64::consts::TAU * f0 * k as f64 * dt + 0.4).sin())
                .collect();
            let lines = spectral_lines_runs(&[&tone], dt);
            assert_eq!(lines.len(), 1, "{f0}: {lines:?}");
            assert!((lines[0] - f0).abs() < 0.05 * resolution, "{f0}: {lines:?}");
            let (a, b) = tone.split_at(n / 3);
            let pooled = spectral_lines_runs(&[a, b], dt);
            assert!(
                (pooled[0] - f0).abs() < 0.05 * resolution,
                "{f0}: {pooled:?}"
            );
        }
        assert!(spectral_lines_runs(&[&w], dt).is_empty());
        let mut acc = 0.0;
        let walk: Vec<f64> = w
            .iter()
            .map(|v| {
                acc += 0.01 * v;
                acc + v
            })
            .collect();
        assert!(spectral_lines_runs(&[&walk], dt).is_empty());
        let e = normals(n, 6);
        let (f0, bw) = (12.0, 0.6);
        let resonance = resonance_in(&w, &e, (f0, bw), dt);
        assert!(spectral_lines_runs(&[&resonance], dt).is_empty());
    }

    /// The Gaussian interpolation of a Hann-windowed tone is biased by at most 0.016 bin (the
    /// figure the docs above state), at any offset from a bin.
    #[test]
    fn gaussian_interpolation_bias_is_at_most_0_016_bin() {
        let n = 4096;
        let window = hann(n);
        let mut worst: f64 = 0.0;
        for j in 0..=50 {
            let f_bins = 100.0 + f64::from(j) / 100.0;
            let (mut re, mut im): (Vec<f64>, Vec<f64>) = (0..n)
                .map(|k| {
                    let ph = std::f64::consts::TAU * f_bins * k as f64 / n as f64 + 0.3;
                    (ph.cos() * window[k], 0.0)
                })
                .unzip();
            noise::fft::fft(&mut re, &mut im);
            let p: Vec<f64> = (0..n / 2).map(|i| re[i] * re[i] + im[i] * im[i]).collect();
            let i = (1..n / 2 - 1)
                .max_by(|&a, &b| p[a].total_cmp(&p[b]))
                .unwrap();
            let est = i as f64 + gaussian_vertex(p[i - 1], p[i], p[i + 1]).0;
            worst = worst.max((est - f_bins).abs());
        }
        assert!(worst <= 0.0161, "{worst}");
        assert!(worst > 0.01, "{worst}");
    }

    /// Tones halfway between the 4096-sample bins (0.574, 3.210 and 31.70 Hz at 100 Hz, where the
    /// search's interpolation is least certain), 6-12 times the background of the search's
    /// spectrum, hidden in white noise, a flicker-like sum of Gauss-Markov processes (time
    /// constants 1-1024 s) and a slow random walk, in three runs of 2^18 + 1000 samples (each its
    /// own noise and phases): each is found and measured on the runs' 2^18-sample segments
    /// (resolution 100 / 2^18 = 0.00038 Hz) to within a tenth of that resolution (the
    /// interpolation's bias is at most 0.016 of it, the noise's about 0.01 here), 1/640 of the
    /// search's resolution; the runs' frequency resolution is reported as that.
    #[test]
    fn line_frequencies_measured_to_the_runs_resolution() {
        let dt = 0.01;
        let n = (1 << 18) + 1000;
        let coarse = 1.0 / (4096.0 * dt);
        let tones = [23.5 * coarse, 131.5 * coarse, 1298.5 * coarse];
        let runs: Vec<Vec<f64>> = (0..3u64)
            .map(|r| {
                let w = normals(n, 40 + r);
                let g = normals(n, 50 + r);
                let flicker = flicker_like(&g, dt);
                let mut walk = 0.0;
                (0..n)
                    .map(|k| {
                        walk += 0.003 * g[(k + 104_729) % n];
                        let t = k as f64 * dt;
                        let tone: f64 = tones
                            .iter()
                            .enumerate()
                            .map(|(j, f)| {
                                let phase = 0.7 * (r as f64 + 1.0) + j as f64;
                                0.15 * (std::f64::consts::TAU * f * t + phase).sin()
                            })
                            .sum();
                        w[k] + flicker[k] + walk + tone
                    })
                    .collect()
            })
            .collect();
        let xs: Vec<&[f64]> = runs.iter().map(Vec::as_slice).collect();
        let fine = line_frequency_resolution_hz(&xs, dt).expect("long enough");
        assert!(
            (fine - 1.0 / ((1 << 18) as f64 * dt)).abs() < 1e-12,
            "{fine}"
        );
        let lines = spectral_lines_runs(&xs, dt);
        for f0 in tones {
            let nearest = lines
                .iter()
                .copied()
                .min_by(|a, b| (a - f0).abs().total_cmp(&(b - f0).abs()))
                .expect("a line");
            eprintln!(
                "{f0} Hz: {nearest} Hz, {:+.4} of the resolution",
                (nearest - f0) / fine
            );
            assert!(
                (nearest - f0).abs() < 0.1 * fine,
                "{f0}: {nearest} ({:.3} of the resolution), lines {lines:?}",
                (nearest - f0) / fine
            );
        }
        assert_eq!(lines.len(), tones.len(), "{lines:?}");
    }

    /// A tone whose frequency moves between runs (like the ADIS16405's mount: 0.564 Hz in two
    /// runs, a coarse resolution lower in a third, four lower in a fourth; white noise): the runs'
    /// 4096-sample spectrum shows lines 1 and 4 resolutions apart and falls off too slowly to pass
    /// for one line near 0.56 Hz (checked), so the lines are sought in each run too. The strongest
    /// in the runs' fine spectrum (the two runs that share it) is the first line, measured to a
    /// tenth of the fine resolution; the one a coarse resolution from it is dropped as the same
    /// tone; the one four away is a line of its own. Each run's frequency is a line for the
    /// stand-in test.
    #[test]
    fn a_tone_moving_between_runs_is_one_line_at_the_strongest_frequency() {
        let dt = 0.01;
        let n = 1 << 18;
        let coarse = 1.0 / (4096.0 * dt);
        let f = [0.5643, 0.5643, 0.5643 - coarse, 0.5643 - 4.0 * coarse];
        let runs: Vec<Vec<f64>> = f
            .iter()
            .enumerate()
            .map(|(r, &f)| {
                let w = normals(n, 60 + r as u64);
                let ph = r as f64;
                (0..n)
                    .map(|k| w[k] + 0.1 * (std::f64::consts::TAU * f * k as f64 * dt + ph).sin())
                    .collect()
            })
            .collect();
        let xs: Vec<&[f64]> = runs.iter().map(Vec::as_slice).collect();
        let pooled = coarse_lines(&xs, 4096, dt);
        assert!(
            pooled.iter().all(|g| (g - f[0]).abs() > 2.0 * coarse),
            "{pooled:?}"
        );
        let fine = line_frequency_resolution_hz(&xs, dt).expect("long enough");
        let lines = spectral_lines_runs(&xs, dt);
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!((lines[0] - f[0]).abs() < 0.1 * fine, "{lines:?}");
        assert!((lines[1] - f[3]).abs() < 0.1 * fine, "{lines:?}");
        for g in f {
            assert!(is_spectral_line_runs(&xs, dt, g), "{g}");
        }
    }

    /// A strong tone halfway between two bins of the peak's spectrum (0.5737 Hz at 100 Hz,
    /// amplitude 0.3 in unit white noise) passes for a broad peak (0.09 Hz wide);
    /// [`peak_and_lines_runs`] keeps it a line, and keeps a resonance (AR(2), 0.6 Hz wide at
    /// 12 Hz) a peak.
    #[test]
    fn a_line_is_not_a_broad_peak_and_a_resonance_stays_one() {
        let dt = 0.01;
        let n = 1 << 18;
        let w = normals(n, 8);
        let f0 = 23.5 / (4096.0 * dt);
        let tone: Vec<f64> = (0..n)
            .map(|k| w[k] + 0.3 * (std::f64::consts::TAU * f0 * k as f64 * dt).sin())
            .collect();
        assert!(broad_peak(&tone, dt).is_some());
        let (peak, lines) = peak_and_lines_runs(&[&tone], dt);
        assert_eq!(peak, None);
        assert_eq!(lines.len(), 1, "{lines:?}");
        let e = normals(n, 9);
        let (fr, bw) = (12.0, 0.6);
        let resonance = resonance_in(&w, &e, (fr, bw), dt);
        let (peak, _) = peak_and_lines_runs(&[&resonance], dt);
        assert!(
            peak.is_some_and(|p| (p.frequency_hz - fr).abs() < 0.05),
            "{peak:?}"
        );
    }

    /// Clean runs (white noise and flicker-like noise, no tone) show no line, alone or four
    /// together (each run's spectrum searched too): 20 sets of four runs of 2^16 samples (measured
    /// 0 lines in 60 sets, 240 runs).
    #[test]
    fn clean_runs_show_no_line() {
        let dt = 0.01;
        let n = 1 << 16;
        for set in 0..20u64 {
            let runs: Vec<Vec<f64>> = (0..4u64)
                .map(|r| {
                    let w = normals(n, 1000 * set + 10 * r);
                    let flicker = flicker_like(&normals(n, 1000 * set + 10 * r + 1), dt);
                    w.iter().zip(&flicker).map(|(w, f)| w + f).collect()
                })
                .collect();
            let xs: Vec<&[f64]> = runs.iter().map(Vec::as_slice).collect();
            assert!(spectral_lines_runs(&xs[..1], dt).is_empty(), "set {set}");
            assert!(spectral_lines_runs(&xs, dt).is_empty(), "set {set}");
        }
    }
}
