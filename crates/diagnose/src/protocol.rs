//! The drift protocol: one procedure applied identically to a measured static log and to logs
//! simulated from a model, so that their drifts can be compared (docs/drift.md).
//!
//! A log is cut into segments of each horizon's length. Before each segment the user's static
//! calibration is applied: the bias of every channel is estimated (not at all, from the whole
//! log's mean, or from the mean over a window just before the segment) and removed, the
//! accelerometers referred to the specific force (0, 0, -g) of a level IMU (Woodman §3.2.1 for
//! the gyro, §4.2 for the accelerometer); the attitude starts either perfect (level, north) or
//! levelled from the calibrated accelerometers' mean over a window (roll = atan2(-f_y, -f_z),
//! pitch = atan2(f_x, sqrt(f_y^2 + f_z^2)), heading north). Each segment is then dead-reckoned
//! from rest with the project's mechanisation (`strapdown`, `Accurate` scheme) and its error
//! against the static truth read at the end (`strapdown::nav_error`).
//!
//! The Earth the segments are dead-reckoned on is the protocol's `latitude_deg`: the round,
//! rotating WGS-84 Earth at that latitude with the height held (a known height), or Woodman's
//! flat, non-rotating Earth (`None`). On the round Earth a static log's gyros read Earth rate and
//! its accelerometers local gravity: the calibration refers every channel to what a static, level,
//! north-facing IMU reads there (`strapdown::RoundEarth::static_imu`), so Earth rate is kept as
//! signal and only the rest is removed as bias; logs simulated from a model read the same ideal
//! values ([`Protocol::ideal`]).

use noise::units::STANDARD_GRAVITY_MPS2 as G_MPS2;
use noise::Channel;
use serde::Serialize;
use strapdown::earth::Place;
use strapdown::{nav_error, Attitude, EarthModel, NavState, RoundEarth, Scheme, Vertical};

/// The latitude a log is taken to be recorded at when none is given, deg (the scenarios'
/// default, montecarlo's `DEFAULT_LATITUDE_DEG`).
pub const DEFAULT_LATITUDE_DEG: f64 = 45.0;

/// The round, rotating WGS-84 Earth at `latitude_deg` with the height held at 0 m, or Woodman's
/// flat Earth (`None`).
pub fn earth_at(latitude_deg: Option<f64>) -> EarthModel {
    match latitude_deg {
        None => EarthModel::Flat {
            gravity_mps2: G_MPS2,
        },
        Some(lat) => EarthModel::Round(RoundEarth {
            vertical: Vertical::Held,
            ..RoundEarth::at(Place::from_deg(lat, 0.0, 0.0))
        }),
    }
}

/// What a static, level, north-facing IMU reads on [`earth_at`]`(latitude_deg)` (gx gy gz ax ay
/// az): on the flat Earth zero rate and (0, 0, -g); on the round one Earth rate
/// (Omega cos L, 0, -Omega sin L) and normal gravity.
pub fn ideal_at(latitude_deg: Option<f64>) -> [f64; 6] {
    let (g, f) = earth_at(latitude_deg).static_imu(&Attitude::identity());
    [g.0.x, g.0.y, g.0.z, f.0.x, f.0.y, f.0.z]
}

/// How the bias is removed before each segment.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Calibration {
    /// Nothing removed: the raw readings are integrated.
    None,
    /// Each channel's mean over the whole log (the ideal reading added back).
    LogMean,
    /// Each channel's mean over `window_s` just before the segment.
    Window { window_s: f64 },
}

impl Calibration {
    /// `none`, `log-mean` or `window:TIME`, the time read by `seconds` (e.g.
    /// `noise::units::duration_s`); the message says what is expected.
    pub fn parse(
        text: &str,
        seconds: &dyn Fn(&str) -> Result<f64, String>,
    ) -> Result<Calibration, String> {
        match text {
            "none" => Ok(Calibration::None),
            "log-mean" => Ok(Calibration::LogMean),
            t => match t.strip_prefix("window:") {
                Some(w) => Ok(Calibration::Window {
                    window_s: seconds(w)?,
                }),
                None => Err("expected none, log-mean or window:TIME (e.g. window:60s)".into()),
            },
        }
    }
}

/// How the attitude starts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Initialisation {
    /// Level and north, as the truth.
    Perfect,
    /// Roll and pitch from the calibrated accelerometers' mean over `window_s` before the segment.
    Levelled { window_s: f64 },
}

impl Initialisation {
    /// `perfect` or `level:TIME`, the time read by `seconds`; the message says what is expected.
    pub fn parse(
        text: &str,
        seconds: &dyn Fn(&str) -> Result<f64, String>,
    ) -> Result<Initialisation, String> {
        match text {
            "perfect" => Ok(Initialisation::Perfect),
            t => match t.strip_prefix("level:") {
                Some(w) => Ok(Initialisation::Levelled {
                    window_s: seconds(w)?,
                }),
                None => Err("expected perfect or level:TIME (e.g. level:10s)".into()),
            },
        }
    }
}

/// The whole protocol.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Protocol {
    pub calibration: Calibration,
    pub initialisation: Initialisation,
    /// Segment lengths, s.
    pub horizons_s: Vec<f64>,
    /// Segments start every half segment instead of every segment.
    pub overlapping: bool,
    /// The latitude of the round, rotating Earth the segments are dead-reckoned on, deg (height
    /// held at 0 m); `None`: Woodman's flat Earth.
    pub latitude_deg: Option<f64>,
}

impl Default for Protocol {
    fn default() -> Self {
        Protocol {
            calibration: Calibration::LogMean,
            initialisation: Initialisation::Perfect,
            horizons_s: vec![10.0, 60.0, 600.0, 3600.0],
            overlapping: false,
            latitude_deg: Some(DEFAULT_LATITUDE_DEG),
        }
    }
}

impl Protocol {
    /// The Earth the segments are dead-reckoned on.
    pub fn earth(&self) -> EarthModel {
        earth_at(self.latitude_deg)
    }

    /// What a static, level, north-facing IMU reads on the protocol's Earth (gx gy gz ax ay az):
    /// the values the calibration refers each channel to and simulated logs are built on.
    pub fn ideal(&self) -> [f64; 6] {
        ideal_at(self.latitude_deg)
    }

    /// The protocol in words, for reports.
    pub fn describe(&self) -> String {
        let cal = match self.calibration {
            Calibration::None => "no bias removed".to_string(),
            Calibration::LogMean => "bias = each channel's mean over the whole log".to_string(),
            Calibration::Window { window_s } => {
                format!("bias = each channel's mean over the {window_s} s before each segment")
            }
        };
        let init = match self.initialisation {
            Initialisation::Perfect => "attitude starts perfect (level, north)".to_string(),
            Initialisation::Levelled { window_s } => format!(
                "roll and pitch levelled from the accelerometers over the {window_s} s before each segment"
            ),
        };
        let earth = match self.latitude_deg {
            None => "on the flat, non-rotating Earth (Woodman)".to_string(),
            Some(lat) => format!(
                "on the rotating WGS-84 Earth at {:.4} deg {}, height held",
                lat.abs(),
                if lat < 0.0 { "S" } else { "N" }
            ),
        };
        format!(
            "{cal}; {init}; {} segments; {earth}",
            if self.overlapping {
                "half-overlapping"
            } else {
                "consecutive, non-overlapping"
            }
        )
    }

    /// Time needed before a segment's start (its calibration and levelling windows), s.
    pub fn lead_s(&self) -> f64 {
        let cal = match self.calibration {
            Calibration::Window { window_s } => window_s,
            _ => 0.0,
        };
        let lev = match self.initialisation {
            Initialisation::Levelled { window_s } => window_s,
            Initialisation::Perfect => 0.0,
        };
        cal.max(lev)
    }

    /// Samples needed before a segment's start (its calibration and levelling windows): each
    /// window is [`window_samples`] long, so a segment never starts before its windows.
    fn lead(&self, dt_s: f64) -> usize {
        let cal = match self.calibration {
            Calibration::Window { window_s } => window_samples(window_s, dt_s),
            _ => 0,
        };
        let lev = match self.initialisation {
            Initialisation::Levelled { window_s } => window_samples(window_s, dt_s),
            Initialisation::Perfect => 0,
        };
        cal.max(lev)
    }

    /// How many segments of `horizon_s` a log of `samples` samples gives (as [`segment_errors`]
    /// cuts them).
    pub fn segments(&self, samples: usize, dt_s: f64, horizon_s: f64) -> usize {
        let len = (horizon_s / dt_s).round() as usize;
        let lead = self.lead(dt_s);
        if len == 0 || samples < lead.saturating_add(len) {
            return 0;
        }
        let stride = if self.overlapping {
            (len / 2).max(1)
        } else {
            len
        };
        (samples - lead - len) / stride + 1
    }
}

/// Samples in a window of `window_s` at `dt_s`: the nearest whole number, at least one (a
/// front end refuses a window shorter than a sample: it names its own setting).
fn window_samples(window_s: f64, dt_s: f64) -> usize {
    ((window_s / dt_s).round() as usize).max(1)
}

/// The errors at the end of each segment of one horizon, in segment order.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SegmentErrors {
    pub horizon_s: f64,
    /// Signed heading, roll and pitch errors, rad.
    pub heading_rad: Vec<f64>,
    pub roll_rad: Vec<f64>,
    pub pitch_rad: Vec<f64>,
    /// Horizontal position and velocity error magnitudes, m and m/s.
    pub pos_horizontal_m: Vec<f64>,
    pub vel_horizontal_mps: Vec<f64>,
}

impl SegmentErrors {
    pub fn len(&self) -> usize {
        self.heading_rad.len()
    }

    pub fn is_empty(&self) -> bool {
        self.heading_rad.is_empty()
    }

    /// The values of one quantity (`Quantity::ALL` order).
    pub fn values(&self, q: Quantity) -> &[f64] {
        match q {
            Quantity::Heading => &self.heading_rad,
            Quantity::Roll => &self.roll_rad,
            Quantity::Pitch => &self.pitch_rad,
            Quantity::PosHorizontal => &self.pos_horizontal_m,
            Quantity::VelHorizontal => &self.vel_horizontal_mps,
        }
    }

    /// Append another log's segments (pooling logs of one sensor).
    pub fn extend(&mut self, other: &SegmentErrors) {
        self.heading_rad.extend_from_slice(&other.heading_rad);
        self.roll_rad.extend_from_slice(&other.roll_rad);
        self.pitch_rad.extend_from_slice(&other.pitch_rad);
        self.pos_horizontal_m
            .extend_from_slice(&other.pos_horizontal_m);
        self.vel_horizontal_mps
            .extend_from_slice(&other.vel_horizontal_mps);
    }
}

/// The drift quantities compared (JSON names in docs/cli.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    Heading,
    Roll,
    Pitch,
    PosHorizontal,
    VelHorizontal,
}

impl Quantity {
    pub const ALL: [Quantity; 5] = [
        Quantity::Heading,
        Quantity::Roll,
        Quantity::Pitch,
        Quantity::PosHorizontal,
        Quantity::VelHorizontal,
    ];

    /// The JSON name.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Heading => "heading_rad",
            Quantity::Roll => "roll_rad",
            Quantity::Pitch => "pitch_rad",
            Quantity::PosHorizontal => "pos_horizontal_m",
            Quantity::VelHorizontal => "vel_horizontal_mps",
        }
    }

    /// The channels (gx gy gz ax ay az) this quantity's drift comes from to first order in a
    /// static, level log (docs/model.md §1: heading from gz; roll from gx, pitch from gy;
    /// horizontal velocity and position from ax, ay and the tilt from gx, gy): a log without
    /// one of them cannot inform it.
    pub fn needs(self) -> &'static [Channel] {
        use Channel::{Ax, Ay, Gx, Gy, Gz};
        match self {
            Quantity::Heading => &[Gz],
            Quantity::Roll => &[Gx],
            Quantity::Pitch => &[Gy],
            Quantity::PosHorizontal | Quantity::VelHorizontal => &[Gx, Gy, Ax, Ay],
        }
    }
}

/// The segment errors of a static log for one horizon under `protocol`. `channels` are gx gy gz
/// (rad/s) and ax ay az (m/s^2); a missing channel (None) reads its ideal value.
pub fn segment_errors(
    channels: &[Option<&[f64]>; 6],
    dt_s: f64,
    horizon_s: f64,
    protocol: &Protocol,
) -> SegmentErrors {
    let means = Means::new(channels, protocol);
    segment_errors_with(channels, dt_s, horizon_s, protocol, &means)
}

/// [`segment_errors`] for every horizon of the protocol, sharing the window sums.
pub fn all_segment_errors(
    channels: &[Option<&[f64]>; 6],
    dt_s: f64,
    protocol: &Protocol,
) -> Vec<SegmentErrors> {
    let means = Means::new(channels, protocol);
    protocol
        .horizons_s
        .iter()
        .map(|&h| segment_errors_with(channels, dt_s, h, protocol, &means))
        .collect()
}

thread_local! {
    /// Prefix-sum vectors of [`Means`], returned when it is dropped and reused by the next log on
    /// this thread.
    static PREFIX_POOL: std::cell::RefCell<Vec<Vec<f64>>> = const { std::cell::RefCell::new(Vec::new()) };
}

impl Drop for Means {
    fn drop(&mut self) {
        let done: Vec<Vec<f64>> = self.prefix.drain(..).flatten().collect();
        PREFIX_POOL.with(|pool| {
            let mut pool = pool.borrow_mut();
            // At most one log's worth (six channels) kept per thread.
            pool.extend(done);
            pool.truncate(6);
        });
    }
}

/// Channel means: over the whole log, and prefix sums for window means when the protocol has
/// windows.
struct Means {
    n: usize,
    whole: [Option<f64>; 6],
    prefix: Vec<Option<Vec<f64>>>,
}

impl Means {
    fn new(channels: &[Option<&[f64]>; 6], protocol: &Protocol) -> Means {
        let n = channels
            .iter()
            .flatten()
            .map(|c| c.len())
            .min()
            .unwrap_or(0);
        let windows = matches!(protocol.calibration, Calibration::Window { .. })
            || matches!(protocol.initialisation, Initialisation::Levelled { .. });
        // The means of the six channels from their sums in one pass (`channel_sums`, each in
        // `stats::mean`'s left-to-right order), not six passes of `stats::mean`; none: 0.
        let sums = channel_sums(channels, n);
        let whole = std::array::from_fn(|ch| {
            channels[ch].map(|_| if n == 0 { 0.0 } else { sums[ch] / n as f64 })
        });
        let prefix = channels
            .iter()
            .map(|c| {
                c.filter(|_| windows).map(|c| {
                    // A vector of this thread's pool (a fresh 8 MB one per channel and log costs
                    // its page faults again every time); every entry is written below.
                    let mut p = PREFIX_POOL
                        .with(|pool| pool.borrow_mut().pop())
                        .unwrap_or_default();
                    p.clear();
                    p.reserve(n + 1);
                    let mut s = 0.0;
                    p.push(0.0);
                    for &v in &c[..n] {
                        s += v;
                        p.push(s);
                    }
                    p
                })
            })
            .collect();
        Means { n, whole, prefix }
    }

    fn window(&self, ch: usize, a: usize, b: usize) -> Option<f64> {
        let p = self.prefix[ch].as_ref()?;
        Some((p[b] - p[a]) / (b - a) as f64)
    }
}

/// The sum of each present channel's first `n` samples, each exactly `c[..n].iter().sum()` (the
/// same additions in the same order, from the sum's neutral element -0.0), the six channels in
/// one pass: each sum is a chain of dependent additions, and six chains side by side take about
/// the time of one (the whole-log means were 1.3 % of `imudrift drift`, one chain after the
/// other). A missing channel's entry is -0.0.
fn channel_sums(channels: &[Option<&[f64]>; 6], n: usize) -> [f64; 6] {
    let mut sums = [-0.0f64; 6];
    let present: Vec<(usize, &[f64])> = channels
        .iter()
        .enumerate()
        .filter_map(|(ch, c)| c.map(|c| (ch, &c[..n])))
        .collect();
    if let [(_, xa), (_, xb), (_, xc), (_, xd), (_, xe), (_, xf)] = present[..] {
        // Every channel present, in channel order; the sums in registers.
        let (xb, xc, xd, xe, xf) = (&xb[..n], &xc[..n], &xd[..n], &xe[..n], &xf[..n]);
        let mut s = [-0.0f64; 6];
        for (i, &a) in xa.iter().enumerate() {
            s[0] += a;
            s[1] += xb[i];
            s[2] += xc[i];
            s[3] += xd[i];
            s[4] += xe[i];
            s[5] += xf[i];
        }
        return s;
    }
    for (ch, x) in present {
        sums[ch] = x.iter().fold(-0.0, |s, v| s + v);
    }
    sums
}

fn segment_errors_with(
    channels: &[Option<&[f64]>; 6],
    dt_s: f64,
    horizon_s: f64,
    protocol: &Protocol,
    means: &Means,
) -> SegmentErrors {
    let n = means.n;
    let len = (horizon_s / dt_s).round() as usize;
    let mut out = SegmentErrors {
        horizon_s,
        ..Default::default()
    };
    let lead = protocol.lead(dt_s);
    if len == 0 || n < lead.saturating_add(len) {
        return out;
    }
    let stride = if protocol.overlapping {
        (len / 2).max(1)
    } else {
        len
    };
    let ideal = protocol.ideal();
    let earth = protocol.earth();
    let segments: Vec<Segment> = (lead..=n - len)
        .step_by(stride)
        .map(|start| Segment::new(start, dt_s, protocol, means, &ideal))
        .collect();
    // Up to eight segments at a time in the strapdown's lanes (each lane's numbers are those of
    // a one-lane integrator, bit for bit), the last group in as few lanes as hold it.
    let truth = NavState::default();
    for group in segments.chunks(SEGMENT_LANES) {
        let ends: Vec<NavState> = match group.len() {
            1 => integrate_segments::<1>(channels, dt_s, len, group, &earth, &ideal).to_vec(),
            2 => integrate_segments::<2>(channels, dt_s, len, group, &earth, &ideal).to_vec(),
            3 | 4 => integrate_segments::<4>(channels, dt_s, len, group, &earth, &ideal)
                [..group.len()]
                .to_vec(),
            _ => integrate_segments::<SEGMENT_LANES>(channels, dt_s, len, group, &earth, &ideal)
                [..group.len()]
                .to_vec(),
        };
        for end in &ends {
            let e = nav_error(end, &truth);
            out.heading_rad.push(e.yaw_rad);
            out.roll_rad.push(e.roll_rad);
            out.pitch_rad.push(e.pitch_rad);
            out.pos_horizontal_m.push(e.pos_horizontal_m());
            out.vel_horizontal_mps.push(e.vel_horizontal_mps());
        }
    }
    out
}

/// Segments dead-reckoned together, one per strapdown lane.
const SEGMENT_LANES: usize = 8;

/// One segment: its first sample, the bias removed from each channel and its initial state.
#[derive(Clone, Copy)]
struct Segment {
    start: usize,
    offset: [f64; 6],
    init: NavState,
}

impl Segment {
    /// The user's calibration and initialisation before the segment starting at `start`.
    fn new(
        start: usize,
        dt_s: f64,
        protocol: &Protocol,
        means: &Means,
        ideal: &[f64; 6],
    ) -> Segment {
        let offset: [f64; 6] = std::array::from_fn(|ch| match protocol.calibration {
            Calibration::None => 0.0,
            Calibration::LogMean => means.whole[ch].map_or(0.0, |m| m - ideal[ch]),
            Calibration::Window { window_s } => {
                let w = window_samples(window_s, dt_s);
                means
                    .window(ch, start - w, start)
                    .map_or(0.0, |m| m - ideal[ch])
            }
        });
        let attitude = match protocol.initialisation {
            Initialisation::Perfect => Attitude::identity(),
            Initialisation::Levelled { window_s } => {
                let w = window_samples(window_s, dt_s);
                let f: [f64; 3] = noise::Channel::of(noise::Sensor::Accel).map(|c| {
                    let ch = c.index();
                    means
                        .window(ch, start - w, start)
                        .map_or(ideal[ch], |m| m - offset[ch])
                });
                let roll = (-f[1]).atan2(-f[2]);
                let pitch = f[0].atan2(f[1].hypot(f[2]));
                Attitude::from_euler_rad(roll, pitch, 0.0)
            }
        };
        let init = NavState {
            attitude,
            ..NavState::default()
        };
        Segment {
            start,
            offset,
            init,
        }
    }
}

/// Samples ahead of the one a lane reads that [`integrate_segments`] asks the cache for: four
/// chunks of [`strapdown::CHUNK`] samples, about a thousand strapdown steps of eight lanes.
/// Up to eight lanes read six channels each at as many places of the log (48 streams), more than
/// the hardware prefetcher follows: without the hint each chunk waited on its cache misses (the
/// loads were 8.5 % of `imudrift drift`'s time, 2026-11-26 profile in docs/performance.md).
const PREFETCH_AHEAD: usize = 32;

/// Hint the CPU to bring the cache line of `x[i]` into the first-level cache. A hint only: no
/// value changes, and an index past the end is allowed (a prefetch never faults, and the address
/// is only computed, never dereferenced). No-op off x86_64.
#[inline(always)]
fn prefetch(x: &[f64], i: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: `_mm_prefetch` needs SSE, which every x86_64 CPU has; it reads no memory and
        // never faults, so any address is sound (the pointer is computed with `wrapping_add`,
        // which has no in-bounds requirement).
        unsafe { _mm_prefetch::<_MM_HINT_T0>(x.as_ptr().wrapping_add(i).cast::<i8>()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (x, i);
}

/// Dead-reckon `segments` (1 to `L` of them; lanes beyond them repeat the last segment, and the
/// caller reads only the first `segments.len()` states) for `len` samples each from rest with the
/// `Accurate` scheme: sample k of a segment reads each channel's value less the segment's offset
/// (a missing channel its ideal value). Returns each lane's final state.
fn integrate_segments<const L: usize>(
    channels: &[Option<&[f64]>; 6],
    dt_s: f64,
    len: usize,
    segments: &[Segment],
    earth: &EarthModel,
    ideal: &[f64; 6],
) -> [NavState; L] {
    let lane: [Segment; L] = std::array::from_fn(|l| segments[l.min(segments.len() - 1)]);
    let init: [NavState; L] = std::array::from_fn(|l| lane[l].init);
    let mut nav = earth.lanes::<L>(Scheme::Accurate, &init);
    nav.integrate(len, dt_s, |first, chunk| {
        for (c, channel) in channels.iter().enumerate() {
            for (l, seg) in lane.iter().enumerate() {
                let from = seg.start + first;
                if let Some(x) = channel {
                    prefetch(x, from + PREFETCH_AHEAD);
                }
                for (j, s) in chunk.iter_mut().enumerate() {
                    s[c][l] = channel.map_or(ideal[c], |x| x[from + j] - seg.offset[c]);
                }
            }
        }
    });
    std::array::from_fn(|l| nav.state(l))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn walk(n: usize, seed: u64, step: f64, offset: f64) -> Vec<f64> {
        let mut s = seed;
        let mut x = offset;
        (0..n)
            .map(|_| {
                s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
                let mut z = s;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                z ^= z >> 31;
                x += step * ((z >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
                x + 1e-3 * ((z & 0xffff) as f64 / 65536.0 - 0.5)
            })
            .collect()
    }

    /// The whole-log sums of all six channels in one pass equal each channel's own sum bit for
    /// bit (a first sample of -0.0 included), and with a channel missing too.
    #[test]
    fn channel_sums_equal_each_channels_sum() {
        let n = 10_000;
        let mut chans: Vec<Vec<f64>> = (0..6).map(|c| walk(n, c as u64 + 5, 1e-3, 0.1)).collect();
        chans[2][0] = -0.0;
        chans[4] = vec![-0.0; n];
        let refs: [Option<&[f64]>; 6] = std::array::from_fn(|c| Some(chans[c].as_slice()));
        for m in [0, 1, 7, n - 3] {
            let got = channel_sums(&refs, m);
            for c in 0..6 {
                let want: f64 = chans[c][..m].iter().sum();
                assert_eq!(got[c].to_bits(), want.to_bits(), "channel {c}, {m} samples");
            }
            let mut partial = refs;
            partial[1] = None;
            let got = channel_sums(&partial, m);
            for c in [0, 2, 3, 4, 5] {
                let want: f64 = chans[c][..m].iter().sum();
                assert_eq!(got[c].to_bits(), want.to_bits(), "channel {c}, {m} samples");
            }
        }
    }

    /// Determinism and segmentation: consecutive segments from the start, the same values for
    /// the same input; half-overlapping segments give twice as many less one.
    #[test]
    fn segments_are_cut_as_stated() {
        let n = 30_000;
        let chans: Vec<Vec<f64>> = (0..6)
            .map(|c| walk(n, c as u64 + 1, 1e-5, if c == 5 { -G_MPS2 } else { 0.0 }))
            .collect();
        let refs: [Option<&[f64]>; 6] = std::array::from_fn(|c| Some(chans[c].as_slice()));
        let p = Protocol::default();
        let a = segment_errors(&refs, 0.01, 20.0, &p);
        assert_eq!(a, segment_errors(&refs, 0.01, 20.0, &p));
        assert_eq!(a.len(), 15);
        let overlapping = Protocol {
            overlapping: true,
            ..Protocol::default()
        };
        let b = segment_errors(&refs, 0.01, 20.0, &overlapping);
        assert_eq!(b.len(), 29);
        // Every other overlapping segment is a consecutive one.
        assert_eq!(b.heading_rad[2], a.heading_rad[1]);
    }

    /// Segments dead-reckoned in lanes (groups of 8, 4, 2 and 1) give each segment's numbers of
    /// a one-lane integrator bit for bit, under both calibrations and initialisations.
    #[test]
    fn segments_in_lanes_equal_segments_alone() {
        let n = 30_000;
        let chans: Vec<Vec<f64>> = (0..6)
            .map(|c| walk(n, c as u64 + 11, 1e-4, if c == 5 { -G_MPS2 } else { 0.0 }))
            .collect();
        let refs: [Option<&[f64]>; 6] = std::array::from_fn(|c| Some(chans[c].as_slice()));
        let protocols = [
            Protocol::default(),
            Protocol {
                calibration: Calibration::Window { window_s: 5.0 },
                initialisation: Initialisation::Levelled { window_s: 5.0 },
                overlapping: true,
                ..Protocol::default()
            },
        ];
        // 300 s: 30, 15, 7, 3 and 1 segments (lanes 8+8+8+4+2, 8+4+2+1, 4+2+1...).
        for p in &protocols {
            let means = Means::new(&refs, p);
            for horizon in [10.0, 20.0, 40.0, 100.0, 300.0] {
                let got = segment_errors_with(&refs, 0.01, horizon, p, &means);
                let len = (horizon / 0.01_f64).round() as usize;
                let stride = if p.overlapping { len / 2 } else { len };
                let starts = (p.lead(0.01)..=n - len).step_by(stride);
                let mut count = 0;
                for (i, start) in starts.enumerate() {
                    let seg = Segment::new(start, 0.01, p, &means, &p.ideal());
                    let end =
                        integrate_segments::<1>(&refs, 0.01, len, &[seg], &p.earth(), &p.ideal())
                            [0];
                    let e = nav_error(&end, &NavState::default());
                    assert_eq!(got.heading_rad[i].to_bits(), e.yaw_rad.to_bits());
                    assert_eq!(got.roll_rad[i].to_bits(), e.roll_rad.to_bits());
                    assert_eq!(
                        got.pos_horizontal_m[i].to_bits(),
                        e.pos_horizontal_m().to_bits()
                    );
                    count += 1;
                }
                assert_eq!(got.len(), count, "horizon {horizon} s");
            }
        }
    }

    /// A constant accelerometer bias is invisible after a window calibration, and with a
    /// levelled start a constant tilt-like accelerometer error gives no position error either.

    #[test]
    fn segment_counts_are_those_cut() {
        let n = 10_007;
        let x = walk(n, 3, 1e-3, 0.0);
        let chans = [Some(x.as_slice()), None, None, None, None, None];
        for (calibration, overlapping) in [
            (Calibration::LogMean, false),
            (Calibration::Window { window_s: 7.0 }, true),
            (Calibration::None, true),
        ] {
            let p = Protocol {
                calibration,
                initialisation: Initialisation::Levelled { window_s: 3.0 },
                horizons_s: vec![],
                overlapping,
                latitude_deg: None,
            };
            for h in [1.0, 9.99, 33.0, 100.0, 200.0] {
                let cut = segment_errors(&chans, 0.01, h, &p).len();
                assert_eq!(p.segments(n, 0.01, h), cut, "{p:?} {h}");
            }
        }
    }
    #[test]
    fn window_calibration_removes_a_constant_bias() {
        // The calibration's algebra on Woodman's flat Earth (a levelled, tilted start reads no
        // Earth rate there; the round Earth's readings are tested through the commands).
        let flat = || Protocol {
            latitude_deg: None,
            ..Protocol::default()
        };
        let n = 20_000;
        let dt = 0.01;
        let ax = vec![0.05; n];
        let az = vec![-G_MPS2 + 0.02; n];
        let refs: [Option<&[f64]>; 6] = [None, None, None, Some(&ax), None, Some(&az)];
        let raw = Protocol {
            calibration: Calibration::None,
            ..flat()
        };
        let e = segment_errors(&refs, dt, 10.0, &raw);
        // Woodman eq (10): s = eps t^2 / 2 for the uncalibrated bias.
        let law = 0.05 * 100.0 / 2.0;
        assert!((e.pos_horizontal_m[0] / law - 1.0).abs() < 2.0 * dt / 10.0);
        let windowed = Protocol {
            calibration: Calibration::Window { window_s: 5.0 },
            initialisation: Initialisation::Levelled { window_s: 5.0 },
            ..flat()
        };
        let e = segment_errors(&refs, dt, 10.0, &windowed);
        assert_eq!(e.len(), (n - 500) / 1000);
        assert!(e.pos_horizontal_m.iter().all(|p| p.abs() < 1e-9), "{e:?}");
        // Levelling from a raw tilt: with no calibration the accelerometer "bias" reads as a
        // tilt, which levelling takes out exactly (the classic bias-tilt cancellation).
        let levelled = Protocol {
            calibration: Calibration::None,
            initialisation: Initialisation::Levelled { window_s: 5.0 },
            ..flat()
        };
        let e = segment_errors(&refs, dt, 10.0, &levelled);
        assert!(e.pos_horizontal_m.iter().all(|p| p.abs() < 1e-6), "{e:?}");
        assert!(
            e.pitch_rad.iter().all(|p| p.abs() > 1e-3),
            "the start is tilted: {e:?}"
        );
    }
}
