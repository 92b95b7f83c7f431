//! The per-run error state of an IMU: each channel runs its terms' generators (`terms/<effect>.rs`,
//! exact discretisation at the sample interval, docs/model.md §3) in the registry's generation
//! order, behind the axis' output filter where it has one. One random sub-stream per (channel,
//! term), so adding a term does not reshuffle others.

use crate::block::{BlockTerms, Linear};
use crate::channel::Channel;
use crate::effect::Sensor;
use crate::model::SensorModel;
use crate::temperature::TemperatureProfile;
use crate::terms::output_filter::{FilterState, OutputFilter};
use crate::terms::{GenContext, Generate, Generator, RawClock, Stage, GENERATION_ORDER};
use crate::{block_rng, calibration_rng, term_rng, NormalStream};
use nalgebra::Vector3;

use crate::discrete::{fused4, FusedLane};
pub use crate::discrete::{GaussMarkovBank, RandomWalk, HOLD_FRACTION};
pub use crate::terms::quantization::Quantizer;
pub use crate::terms::resonance::Resonator;
pub use crate::terms::white_noise::WhiteNoiseSampler;

/// Samples per sub-block of `ChannelErrors::fill_static` (any value gives the same values).
const FILL_CHUNK: usize = 512;
/// Raw (internal-rate) samples per sub-block behind an output filter, at least one output sample's
/// worth (any value gives the same values; bounds the memory a large decimation needs).
const RAW_CHUNK: usize = 4096;

/// The error generator of one output channel (one axis of one triad) for one run.
#[derive(Clone, Debug)]
pub struct ChannelErrors {
    dt_s: f64,
    /// Row of (I + scale factor + misalignment) applied to the ideal triad input.
    row: [f64; 3],
    /// Constant bias plus this run's turn-on bias draw.
    bias: f64,
    /// The generators of the terms added to the raw samples, in generation order.
    raw: Vec<Generator>,
    /// The generators acting on the output register after the filter, in generation order.
    output: Vec<Generator>,
    /// Interval of the raw error processes: the output interval, or the output filter's internal one.
    dt_raw: f64,
    /// The output filter's state (None: the raw samples are the output).
    filter: Option<FilterState>,
    /// The linear Gaussian raw terms generated at the output rate behind a decimating FIR
    /// filter (`crate::block`); made at the first sample, after the calibration.
    block: Option<BlockTerms>,
    /// (seed, run, channel) of a channel whose filter suits the block path, until it is made.
    block_source: Option<(u64, u64, u64)>,
    /// A block's normal draws (reused; its contents never outlive a call).
    scratch: Vec<f64>,
    /// The second and third terms' draws when terms run in one pass ([`raw_terms`]).
    scratch2: Vec<f64>,
    scratch3: Vec<f64>,
    /// The k the next call must bring (the states advance one step per call); checked in debug
    /// builds only (keeping it up to date costs ~30 % of the sample time in release).
    #[cfg(debug_assertions)]
    next_k: u64,
}

impl ChannelErrors {
    /// Each term of the channel's axis makes its generator (its per-run draws from its own
    /// stream); the input terms fold into the row and bias, the others run per sample.
    fn new(model: &SensorModel, channel: Channel, dt_s: f64, seed: u64, run: u64) -> ChannelErrors {
        let (sensor, axis_index) = (channel.sensor(), channel.axis());
        let axis = model.axis(sensor, axis_index);
        // This power-on's levels (docs/model.md §2.3): per run and axis a long-term and a
        // short-term draw from the channel's run-to-run stream, which no other draw uses; none
        // without a spread.
        let drawn;
        let axis = if axis.varies_between_runs() {
            drawn = axis.at_run_draws(crate::run_to_run::run_draws(seed, run, channel.index()));
            &drawn
        } else {
            axis
        };
        // The raw processes run at the filter's internal interval.
        let output_filter = axis.get::<OutputFilter>();
        let filter = output_filter.map(|f| FilterState::new(f, dt_s));
        let cx = GenContext {
            axis: axis_index,
            dt_out_s: dt_s,
            dt_raw_s: output_filter.map_or(dt_s, |f| f.internal_dt(dt_s)),
            filter_response: filter.as_ref().map(FilterState::response),
            temperature: &model.temperature,
            temperature_reference_c: model.temperature_reference_c,
        };
        let mut row = [0.0; 3];
        row[axis_index] = 1.0;
        let (mut bias, mut raw, mut output) = (0.0, Vec::new(), Vec::new());
        for effect in GENERATION_ORDER {
            let Some(term) = axis.term(effect) else {
                continue;
            };
            let g = term.generator(&cx, &|| term_rng(seed, run, channel as u64, effect));
            match g.stage() {
                Stage::Input => g.input(&mut row, &mut bias),
                Stage::Raw => raw.push(g),
                Stage::Output => output.push(g),
                Stage::None => {}
            }
        }
        let dt_raw = cx.dt_raw_s;
        let block_source = filter
            .as_ref()
            .filter(|f| f.is_fir() && BlockTerms::suits(f.response(), f.decimation))
            .map(|_| (seed, run, channel as u64));
        ChannelErrors {
            dt_s,
            dt_raw,
            row,
            bias,
            raw,
            output,
            filter,
            block: None,
            block_source,
            scratch: Vec::new(),
            scratch2: Vec::new(),
            scratch3: Vec::new(),
            #[cfg(debug_assertions)]
            next_k: 0,
        }
    }

    /// Reference the slowly varying bias processes (flicker bias instability components and the
    /// Gauss-Markov term) to their values at t = 0 ([`GaussMarkovBank::reference_to_start`]);
    /// random walks already start at 0, white noise and the other terms are unchanged.
    /// Call before the first sample.
    pub fn calibrate_start(&mut self) {
        self.raw.iter_mut().for_each(Generate::calibrate_start);
    }

    /// Reference the slowly varying bias processes (flicker components and the Gauss-Markov term)
    /// to their means over a calibration window of `window_s` seconds before t = 0
    /// ([`GaussMarkovBank::reference_to_window_mean`]); each process's window draws come from its
    /// own calibration stream (`calibration_rng`), so its own stream is untouched.
    /// Call before the first sample.
    fn calibrate_window(&mut self, window_s: f64, seed: u64, run: u64, channel: usize) {
        for g in &mut self.raw {
            let effect = g.effect();
            g.calibrate_window(window_s, &|| {
                calibration_rng(seed, run, channel as u64, effect)
            });
        }
    }

    /// Move the linear Gaussian raw terms (white noise, random walks, the components of
    /// Gauss-Markov banks, resonances) to the block path where the channel's
    /// filter suits it (`crate::block`); the rest stay raw. Once, at the first sample (after the
    /// calibration, which references the banks' states).
    fn prepare_block(&mut self) {
        use crate::terms::bias_instability::BiasInstabilityGenerator::Flicker;
        let Some((seed, run, channel)) = self.block_source.take() else {
            return;
        };
        let Some(f) = self.filter.as_ref() else {
            return;
        };
        let mut comps = Vec::new();
        let mut kept = Vec::new();
        for mut g in std::mem::take(&mut self.raw) {
            let effect = g.effect();
            // Component i of the term draws from the term's block stream i.
            let stream = |i: usize| NormalStream::new(block_rng(seed, run, channel, effect, i));
            let mut first = stream(0);
            let lins = match &mut g {
                Generator::WhiteNoise(w) => {
                    let sd = w.sd();
                    let x0 = sd * crate::discrete::draws(&mut first, &mut self.scratch, 1)[0];
                    vec![Linear::scalar(0.0, sd, x0)]
                }
                Generator::RateRandomWalk(w) => {
                    let (step, state) = w.walk.parts();
                    vec![Linear::scalar(1.0, step, state)]
                }
                Generator::Resonance(r) => {
                    let lane = r.parts().0.lane();
                    let (l11, l21, l22) = lane.chol;
                    vec![Linear {
                        phi: lane.phi,
                        q_chol: [[l11, 0.0], [l21, l22]],
                        dim: 2,
                        state: *lane.state,
                    }]
                }
                Generator::BiasInstability(Flicker(b))
                | Generator::GaussMarkov(b)
                | Generator::SlowGaussMarkov(b)
                | Generator::PowerLaw(b) => {
                    let c = b.parts().0.take_components();
                    kept.push(g);
                    c.into_iter()
                        .map(|(phi, drive, x)| Linear::scalar(phi, drive, x))
                        .collect()
                }
                _ => {
                    kept.push(g);
                    continue;
                }
            };
            let mut first = Some(first);
            for (i, lin) in lins.into_iter().enumerate() {
                comps.push((lin, first.take().unwrap_or_else(|| stream(i))));
            }
        }
        self.raw = kept;
        let rest = NormalStream::new(block_rng(
            seed,
            run,
            channel,
            crate::effect::Effect::OutputFilter,
            0,
        ));
        self.block = Some(BlockTerms::new(f.response(), f.decimation, comps, rest));
    }

    /// The measured value of sample `k` (t = k·dt) given the ideal triad input. Calls must come with
    /// k = 0, 1, 2, ... in order: the stochastic states advance one step per call.
    #[inline]
    pub fn sample(&mut self, k: u64, ideal: &Vector3<f64>) -> f64 {
        let mut v = 0.0;
        Self::fill_with(&mut [self], k, &mut [std::slice::from_mut(&mut v)], |_| {
            ideal
        });
        v
    }

    /// Samples `k0 .. k0 + out.len()` for a constant ideal input (a static IMU). The same values,
    /// bit for bit, as `sample` called for each k in turn (one implementation serves both); a block
    /// is faster: each term runs over the whole block in one loop.
    pub fn fill_static(&mut self, k0: u64, ideal: &Vector3<f64>, out: &mut [f64]) {
        Self::fill_lanes_lockstep(&mut [self], k0, &mut [out], |_| ideal);
    }

    /// Samples `k0 .. k0 + out.len()` for a moving IMU, sample `k0 + i` with ideal input
    /// `ideal[i]` (`ideal.len() >= out.len()`). The same values, bit for bit, as `sample` called for
    /// each k in turn with those inputs; a block is faster, as for [`ChannelErrors::fill_static`].
    pub fn fill_moving(&mut self, k0: u64, ideal: &[Vector3<f64>], out: &mut [f64]) {
        assert!(ideal.len() >= out.len(), "one ideal input per sample");
        Self::fill_lanes_lockstep(&mut [self], k0, &mut [out], |i| &ideal[i]);
    }

    /// [`ChannelErrors::fill_static`] of several runs' generators of one channel (lanes), run l
    /// into `outs[l]`: each run gets exactly the values of its own call, and where the runs' terms
    /// have the same structure (the same terms and output filter; the levels may differ) their
    /// serial recursions run side by side ([`GaussMarkovBank::add_blocks_then`]).
    pub fn fill_static_lanes(
        lanes: &mut [&mut ChannelErrors],
        k0: u64,
        ideal: &Vector3<f64>,
        outs: &mut [&mut [f64]],
    ) {
        Self::fill_lanes(lanes, k0, outs, |_| ideal);
    }

    /// [`ChannelErrors::fill_moving`] of several runs (lanes) with one ideal input, as
    /// [`ChannelErrors::fill_static_lanes`].
    pub fn fill_moving_lanes(
        lanes: &mut [&mut ChannelErrors],
        k0: u64,
        ideal: &[Vector3<f64>],
        outs: &mut [&mut [f64]],
    ) {
        assert!(
            outs.iter().all(|o| ideal.len() >= o.len()),
            "one ideal input per sample"
        );
        Self::fill_lanes(lanes, k0, outs, |i| &ideal[i]);
    }

    /// Whether `other` (another run's generator of the same channel) can be filled in lockstep
    /// with this one: the same raw interval and number of raw terms, and the same output filter
    /// position.
    fn lockstep_with(&self, other: &ChannelErrors) -> bool {
        self.dt_raw.to_bits() == other.dt_raw.to_bits()
            && self.raw.len() == other.raw.len()
            && self.block.is_some() == other.block.is_some()
            && match (&self.filter, &other.filter) {
                (None, None) => true,
                (Some(a), Some(b)) => {
                    (a.decimation, a.preroll, a.raw_done) == (b.decimation, b.preroll, b.raw_done)
                }
                _ => false,
            }
    }

    /// The lanes in lockstep where they can be, else one after the other.
    fn fill_lanes<'a>(
        lanes: &mut [&mut ChannelErrors],
        k0: u64,
        outs: &mut [&mut [f64]],
        ideal: impl Fn(usize) -> &'a Vector3<f64>,
    ) {
        assert_eq!(lanes.len(), outs.len(), "one block per lane");
        lanes.iter_mut().for_each(|l| l.prepare_block());
        let n = outs.first().map_or(0, |o| o.len());
        let lockstep =
            outs.iter().all(|o| o.len() == n) && lanes.iter().all(|l| l.lockstep_with(lanes[0]));
        if lockstep {
            Self::fill_lanes_lockstep(lanes, k0, outs, ideal);
        } else {
            for (l, o) in lanes.iter_mut().zip(outs.iter_mut()) {
                Self::fill_lanes_lockstep(&mut [&mut **l], k0, &mut [&mut **o], &ideal);
            }
        }
    }

    /// Lanes in lockstep ([`ChannelErrors::lockstep_with`]), blocks of one length, in
    /// sub-blocks that keep the draws of one sub-block (the generators' scratch) in L1/L2.
    fn fill_lanes_lockstep<'a>(
        lanes: &mut [&mut ChannelErrors],
        k0: u64,
        outs: &mut [&mut [f64]],
        ideal: impl Fn(usize) -> &'a Vector3<f64>,
    ) {
        let n = outs.first().map_or(0, |o| o.len());
        for first in (0..n).step_by(FILL_CHUNK) {
            let end = (first + FILL_CHUNK).min(n);
            let mut sub: Vec<&mut [f64]> = outs.iter_mut().map(|o| &mut o[first..end]).collect();
            Self::fill_with(lanes, k0 + first as u64, &mut sub, |i| ideal(first + i));
        }
    }

    /// Samples `k0 .. k0 + n` of each lane (`outs[l]`, n long), sample `k0 + i` with ideal input
    /// `ideal(i)`. Each term adds its values to the whole block in turn, in the order (and with
    /// the arithmetic) of one sample, and every term draws from its own stream in sample order, so
    /// neither the block length nor the lanes beside it change any value.
    #[inline]
    fn fill_with<'a>(
        lanes: &mut [&mut ChannelErrors],
        k0: u64,
        outs: &mut [&mut [f64]],
        ideal: impl Fn(usize) -> &'a Vector3<f64>,
    ) {
        let n = outs.first().map_or(0, |o| o.len());
        #[cfg(debug_assertions)]
        for l in lanes.iter_mut() {
            assert_eq!(k0, l.next_k, "samples must be drawn in order");
            l.next_k = k0 + n as u64;
        }
        lanes.iter_mut().for_each(|l| l.prepare_block());
        let mut filters: Vec<FilterState> =
            lanes.iter_mut().filter_map(|l| l.filter.take()).collect();
        match filters.first() {
            None => Self::fill_raw(lanes, k0, 0, outs, ideal),
            Some(f) => {
                // Output sub-blocks of about RAW_CHUNK raw samples over all lanes (the filter's
                // state carries over, so the split changes no value).
                let per = (RAW_CHUNK / lanes.len() / f.decimation).max(1);
                for first in (0..n).step_by(per) {
                    let end = (first + per).min(n);
                    let mut sub: Vec<&mut [f64]> =
                        outs.iter_mut().map(|o| &mut o[first..end]).collect();
                    Self::fill_filtered(lanes, &mut filters, k0 + first as u64, &mut sub, |i| {
                        ideal(first + i)
                    });
                }
                for (l, f) in lanes.iter_mut().zip(filters) {
                    l.filter = Some(f);
                }
                for (l, out) in lanes.iter_mut().zip(outs.iter_mut()) {
                    if let Some(b) = &mut l.block {
                        b.add(out);
                    }
                }
            }
        }
        for (l, out) in lanes.iter_mut().zip(outs.iter_mut()) {
            let dt_s = l.dt_s;
            for g in &mut l.output {
                g.output(k0, dt_s, out);
            }
        }
    }

    /// Output samples `k0 .. k0 + n` of each lane through its output filter (`filters[l]`): the
    /// raw samples up to the one output k0 + n - 1 is read at, each with the ideal input of the
    /// output sample it belongs to (zero-order hold; the pre-roll takes output 0's), then filtered
    /// and read out.
    fn fill_filtered<'a>(
        lanes: &mut [&mut ChannelErrors],
        filters: &mut [FilterState],
        k0: u64,
        outs: &mut [&mut [f64]],
        ideal: impl Fn(usize) -> &'a Vector3<f64>,
    ) {
        let n = outs.first().map_or(0, |o| o.len()) as u64;
        let (d, pre, start) = match filters.first() {
            Some(f) => (f.decimation as u64, f.preroll as u64, f.raw_done),
            None => return,
        };
        let end = pre + (k0 + n - 1) * d + 1;
        let mut raws: Vec<Vec<f64>> = filters
            .iter_mut()
            .map(|f| {
                let mut raw = std::mem::take(&mut f.raw);
                raw.clear();
                raw.resize((end - start) as usize, 0.0);
                raw
            })
            .collect();
        let mut raw_blocks: Vec<&mut [f64]> = raws.iter_mut().map(|r| r.as_mut_slice()).collect();
        Self::fill_raw(lanes, start, pre, &mut raw_blocks, |j| {
            let r = start + j as u64;
            let o = r.saturating_sub(pre).div_ceil(d);
            ideal((o.max(k0) - k0).min(n - 1) as usize)
        });
        FilterState::filter_lanes(filters, start, &raws, k0, outs);
        for (f, raw) in filters.iter_mut().zip(raws) {
            f.raw = raw;
        }
    }

    /// Raw samples `k0 .. k0 + n` of each lane at the raw interval (time t = (k - preroll)
    /// dt_raw), every term but the filter, the outliers and the quantiser.
    #[inline]
    fn fill_raw<'a>(
        lanes: &mut [&mut ChannelErrors],
        k0: u64,
        preroll: u64,
        outs: &mut [&mut [f64]],
        ideal: impl Fn(usize) -> &'a Vector3<f64>,
    ) {
        let Some(dt_raw) = lanes.first().map(|l| l.dt_raw) else {
            return;
        };
        let clock = RawClock {
            k0,
            dt_s: dt_raw,
            offset_s: preroll as f64 * dt_raw,
        };
        if lanes.len() == 1 {
            // One run (`sample` per sample, `fill_static` per block): the lane on the stack, not
            // in a vector allocated per call.
            if let (Some(l), Some(out)) = (lanes.first_mut(), outs.first_mut()) {
                let mut one = [raw_lane(l, out, &ideal)];
                raw_terms_lanes(&mut one, clock);
            }
            return;
        }
        let mut raw: Vec<RawLane> = lanes
            .iter_mut()
            .zip(outs.iter_mut())
            .map(|(l, out)| raw_lane(l, out, &ideal))
            .collect();
        raw_terms_lanes(&mut raw, clock);
    }
}

/// A run's raw block started at its ideal reading (row times the ideal input, plus the bias), as
/// a lane of [`raw_terms_lanes`].
fn raw_lane<'l, 'a>(
    l: &'l mut ChannelErrors,
    out: &'l mut [f64],
    ideal: &impl Fn(usize) -> &'a Vector3<f64>,
) -> RawLane<'l> {
    for (i, v) in out.iter_mut().enumerate() {
        let x = ideal(i);
        *v = l.row[0] * x.x + l.row[1] * x.y + l.row[2] * x.z + l.bias;
    }
    RawLane {
        raw: &mut l.raw,
        out,
        s: [&mut l.scratch, &mut l.scratch2, &mut l.scratch3],
    }
}

/// The pass [`raw_terms`] makes over the terms from here: a flicker bias instability followed by
/// a rate random walk and a resonance, by one of them, or by both (adjacent in the generation
/// order, and in most fitted models) run in one loop; any other term alone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pass {
    BankWalkResonance,
    BankWalk,
    BankResonance,
    /// A flicker bias instability alone: one loop already; side by side in lanes.
    Bank,
    Alone,
}

impl Pass {
    fn of(raw: &[Generator]) -> Pass {
        use crate::terms::bias_instability::BiasInstabilityGenerator::Flicker;
        use Generator::{BiasInstability, RateRandomWalk, Resonance};
        match raw {
            [BiasInstability(Flicker(_)), RateRandomWalk(_), Resonance(_), ..] => {
                Pass::BankWalkResonance
            }
            [BiasInstability(Flicker(_)), RateRandomWalk(_), ..] => Pass::BankWalk,
            [BiasInstability(Flicker(_)), Resonance(_), ..] => Pass::BankResonance,
            [BiasInstability(Flicker(_)), ..] => Pass::Bank,
            _ => Pass::Alone,
        }
    }

    /// Terms the pass covers.
    fn terms(self) -> usize {
        match self {
            Pass::BankWalkResonance => 3,
            Pass::BankWalk | Pass::BankResonance => 2,
            Pass::Bank | Pass::Alone => 1,
        }
    }
}

/// Add the raw terms `raw`'s values to the raw samples `out`, term after term in generation
/// order; the terms of a [`Pass`] in one loop ([`GaussMarkovBank::add_block_then`]): the values
/// of the terms one after the other, bit for bit, in about the time of the slowest alone.
#[inline]
fn raw_terms(raw: &mut [Generator], clock: RawClock, out: &mut [f64], s: [&mut Vec<f64>; 3]) {
    let mut lane = [RawLane { raw, out, s }];
    raw_terms_lanes(&mut lane, clock);
}

/// One run's share of [`raw_terms_lanes`]: its channel's raw generators, its block, its scratch.
struct RawLane<'a> {
    raw: &'a mut [Generator],
    out: &'a mut [f64],
    s: [&'a mut Vec<f64>; 3],
}

/// [`raw_terms`] of several runs' generators of one channel (lanes) over blocks of one length:
/// each lane gets exactly the values of its own `raw_terms`; the fused passes run the lanes side
/// by side ([`GaussMarkovBank::add_blocks_then`]), their serial chains in one loop. From the first
/// term where the lanes' passes differ, each lane runs its own.
fn raw_terms_lanes(lanes: &mut [RawLane], clock: RawClock) {
    use crate::terms::bias_instability::BiasInstabilityGenerator::Flicker;
    use Generator::{BiasInstability, RateRandomWalk, Resonance};
    let Some(count) = lanes.first().map(|l| l.raw.len()) else {
        return;
    };
    let mut i = 0;
    while i < count {
        let pass = Pass::of(&lanes[0].raw[i..]);
        if lanes
            .iter()
            .any(|l| l.raw.len() != count || Pass::of(&l.raw[i..]) != pass)
        {
            for l in lanes.iter_mut() {
                let [s0, s1, s2] = &mut l.s;
                raw_terms(&mut l.raw[i..], clock, l.out, [s0, s1, s2]);
            }
            return;
        }
        match pass {
            Pass::BankWalkResonance | Pass::BankWalk | Pass::BankResonance | Pass::Bank => {
                for group in lanes.chunks_mut(fused4::LANES) {
                    if fused_in_lanes(group, i, pass) {
                        continue;
                    }
                    for l in group.iter_mut() {
                        let n = l.out.len();
                        let [s0, s1, s2] = &mut l.s;
                        match &mut l.raw[i..] {
                            [BiasInstability(Flicker(bank)), RateRandomWalk(walk), Resonance(res), ..]
                                if pass == Pass::BankWalkResonance =>
                            {
                                let mut f = (walk.follower(s1, n), res.follower(s2, n));
                                bank.add_raw_then(l.out, s0, &mut f);
                                f.0.finish();
                                f.1.finish();
                            }
                            [bank, ..] if pass == Pass::Bank => bank.add_raw(clock, l.out, s0),
                            [BiasInstability(Flicker(bank)), RateRandomWalk(walk), ..] => {
                                let mut f = walk.follower(s1, n);
                                bank.add_raw_then(l.out, s0, &mut f);
                                f.finish();
                            }
                            [BiasInstability(Flicker(bank)), Resonance(res), ..] => {
                                let mut f = res.follower(s2, n);
                                bank.add_raw_then(l.out, s0, &mut f);
                                f.finish();
                            }
                            _ => unreachable!("Pass::of"),
                        }
                    }
                }
            }
            Pass::Alone => {
                for l in lanes.iter_mut() {
                    l.raw[i].add_raw(clock, l.out, l.s[0]);
                }
            }
        }
        i += pass.terms();
    }
}

/// The fused pass `pass` at term `i` of four lanes in one SIMD loop ([`fused4`]); false (nothing
/// done, nothing drawn) for another number of lanes, a CPU without AVX2, or banks not on one
/// schedule.
fn fused_in_lanes(lanes: &mut [RawLane], i: usize, pass: Pass) -> bool {
    use crate::terms::bias_instability::BiasInstabilityGenerator::Flicker;
    use Generator::{BiasInstability, RateRandomWalk, Resonance};
    let Ok(lanes) = <&mut [RawLane; fused4::LANES]>::try_from(lanes) else {
        return false;
    };
    let banks = lanes.each_mut().map(|l| match &mut l.raw[i] {
        BiasInstability(Flicker(bank)) => Some(&*bank.parts().0),
        _ => None,
    });
    let Some(banks) = banks.into_iter().collect::<Option<Vec<_>>>() else {
        return false;
    };
    let Ok(banks) = <[&GaussMarkovBank; fused4::LANES]>::try_from(banks) else {
        return false;
    };
    if !fused4::available(banks) {
        return false;
    }
    let (walk, res) = match pass {
        Pass::BankWalkResonance => (Some(i + 1), Some(i + 2)),
        Pass::BankWalk => (Some(i + 1), None),
        Pass::BankResonance => (None, Some(i + 1)),
        Pass::Bank => (None, None),
        Pass::Alone => return false,
    };
    let fused: Vec<FusedLane> = lanes
        .iter_mut()
        .map(|l| {
            let n = l.out.len();
            let [s0, s1, s2] = &mut l.s;
            let (head, rest) = l.raw[i..].split_at_mut(1);
            let BiasInstability(Flicker(bank)) = &mut head[0] else {
                unreachable!("checked above")
            };
            let (bank, rng) = bank.parts();
            let nb = bank.draw_block(rng, s0, n);
            let mut walk_gen = None;
            let mut res_gen = None;
            for (k, g) in rest.iter_mut().enumerate() {
                match g {
                    RateRandomWalk(w) if walk == Some(i + 1 + k) => walk_gen = Some(w),
                    Resonance(r) if res == Some(i + 1 + k) => res_gen = Some(r),
                    _ => {}
                }
            }
            let walk = walk_gen.map(|w| {
                crate::discrete::draws(&mut w.rng, s1, n);
                (&mut w.walk, &s1[..n])
            });
            let res = res_gen.map(|r| {
                let (resonator, rng) = r.parts();
                crate::discrete::draws(rng, s2, 2 * n);
                (resonator.lane(), &s2[..2 * n])
            });
            FusedLane {
                bank,
                bank_draws: &s0[..nb],
                walk,
                res,
                out: &mut *l.out,
            }
        })
        .collect();
    let Ok(mut fused) = <[FusedLane; fused4::LANES]>::try_from(fused) else {
        return false;
    };
    fused4::run(&mut fused);
    true
}

/// A model that cannot run at a sample rate: an axis whose output filter does not fit the rate
/// ([`crate::OutputFilter::check_rate`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{axis}.output_filter at {rate_hz} Hz output, decimation {decimation} ({internal_hz} Hz internal): {error}")]
pub struct RateError {
    /// The axis, e.g. "gyro.x".
    pub axis: String,
    pub rate_hz: f64,
    pub decimation: u32,
    pub internal_hz: f64,
    pub error: crate::model_error::ModelError,
}

/// Per-run error state of a whole IMU: six channels (gx gy gz ax ay az).
#[derive(Clone, Debug)]
pub struct ImuErrors {
    channels: [ChannelErrors; 6],
    temperature: TemperatureProfile,
    dt_s: f64,
}

impl ImuErrors {
    /// Can `model` run at sample interval `dt_s`? Every output filter's cutoff must lie below its
    /// internal Nyquist frequency and its response fit [`crate::MAX_RESPONSE`] internal
    /// samples. Check before [`ImuErrors::new`]: a filter that fails gives meaningless values.
    pub fn check_rate(model: &SensorModel, dt_s: f64) -> Result<(), RateError> {
        for sensor in Sensor::ALL {
            for (axis, name) in model.triad(sensor).axes.iter().zip(crate::AXIS_NAMES) {
                if let Some(f) = axis.get::<OutputFilter>() {
                    f.check_rate(dt_s).map_err(|error| RateError {
                        axis: format!("{}.{name}", sensor.name()),
                        rate_hz: 1.0 / dt_s,
                        decimation: f.decimation(),
                        internal_hz: 1.0 / f.internal_dt(dt_s),
                        error,
                    })?;
                }
            }
        }
        Ok(())
    }

    /// Draw run `run`'s per-run values (turn-on bias, initial states, phases) from `seed`.
    /// `dt_s` must be finite and > 0, and the model must pass [`ImuErrors::check_rate`] at it.
    pub fn new(model: &SensorModel, dt_s: f64, seed: u64, run: u64) -> ImuErrors {
        assert!(
            dt_s.is_finite() && dt_s > 0.0,
            "sample interval must be > 0, got {dt_s}"
        );
        ImuErrors {
            channels: Channel::ALL.map(|c| ChannelErrors::new(model, c, dt_s, seed, run)),
            temperature: model.temperature.clone(),
            dt_s,
        }
    }

    /// The same run with the bias perfectly calibrated at turn-on: every channel's flicker and
    /// Gauss-Markov bias processes are referenced to their value at t = 0, so the error they add is
    /// b(t) - b(0) (`ChannelErrors::calibrate_start`). The draws are those of `new`; only the
    /// offsets differ. Call before the first sample.
    pub fn with_calibrated_start(mut self) -> ImuErrors {
        self.channels
            .iter_mut()
            .for_each(ChannelErrors::calibrate_start);
        self
    }

    /// The same run (`seed`, `run` must be those given to `new`) with the bias calibrated by
    /// averaging the static output over a window of `window_s` seconds (finite, > 0) before t = 0:
    /// every channel's flicker and Gauss-Markov bias processes are referenced to their window
    /// mean m, so the error they add is b(t) - m ([`GaussMarkovBank::reference_to_window_mean`]).
    /// The draws of `new` are unchanged; the window means come from separate calibration streams.
    /// Call before the first sample.
    pub fn with_calibration_window(mut self, window_s: f64, seed: u64, run: u64) -> ImuErrors {
        assert!(
            window_s.is_finite() && window_s > 0.0,
            "calibration window must be > 0 s, got {window_s}"
        );
        for (c, ch) in self.channels.iter_mut().enumerate() {
            ch.calibrate_window(window_s, seed, run, c);
        }
        self
    }

    /// Corrupt the ideal sample k (t = k·dt): (measured gyro rad/s, measured accel m/s^2), body frame.
    /// Calls must come with k = 0, 1, 2, ... in order.
    pub fn corrupt(
        &mut self,
        k: u64,
        ideal_gyro: &Vector3<f64>,
        ideal_accel: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let [g0, g1, g2, a0, a1, a2] = &mut self.channels;
        (
            Vector3::new(
                g0.sample(k, ideal_gyro),
                g1.sample(k, ideal_gyro),
                g2.sample(k, ideal_gyro),
            ),
            Vector3::new(
                a0.sample(k, ideal_accel),
                a1.sample(k, ideal_accel),
                a2.sample(k, ideal_accel),
            ),
        )
    }

    /// Samples `k0 .. k0 + n` of a static IMU (constant ideal inputs), channel by channel into
    /// `out[c][..n]` (gx gy gz ax ay az): the same values, bit for bit, as `corrupt` for each k.
    pub fn fill_static(
        &mut self,
        k0: u64,
        ideal_gyro: &Vector3<f64>,
        ideal_accel: &Vector3<f64>,
        out: [&mut [f64]; 6],
    ) {
        for ((c, channel), o) in Channel::ALL.into_iter().zip(&mut self.channels).zip(out) {
            channel.fill_static(k0, if c.is_gyro() { ideal_gyro } else { ideal_accel }, o);
        }
    }

    /// Samples `k0 .. k0 + n` of a moving IMU, sample `k0 + i` with ideal inputs `ideal_gyro[i]`,
    /// `ideal_accel[i]`, channel by channel into `out[c][..n]` (gx gy gz ax ay az): the same
    /// values, bit for bit, as `corrupt` for each k, with each term run over the whole block.
    pub fn fill_moving(
        &mut self,
        k0: u64,
        ideal_gyro: &[Vector3<f64>],
        ideal_accel: &[Vector3<f64>],
        out: [&mut [f64]; 6],
    ) {
        for ((c, channel), o) in Channel::ALL.into_iter().zip(&mut self.channels).zip(out) {
            channel.fill_moving(k0, if c.is_gyro() { ideal_gyro } else { ideal_accel }, o);
        }
    }

    /// [`ImuErrors::fill_static`] of several runs (lanes), run l into `outs[l]`: each run gets
    /// exactly the values of its own call; channel by channel, the runs' serial recursions run
    /// side by side where their terms have one structure ([`ChannelErrors::fill_static_lanes`]).
    pub fn fill_static_lanes(
        errors: &mut [ImuErrors],
        k0: u64,
        ideal_gyro: &Vector3<f64>,
        ideal_accel: &Vector3<f64>,
        outs: &mut [[&mut [f64]; 6]],
    ) {
        for c in Channel::ALL {
            let (mut lanes, mut blocks) = Self::lanes_of(errors, outs, c);
            let ideal = if c.is_gyro() { ideal_gyro } else { ideal_accel };
            ChannelErrors::fill_static_lanes(&mut lanes, k0, ideal, &mut blocks);
        }
    }

    /// [`ImuErrors::fill_moving`] of several runs (lanes) with one ideal input, as
    /// [`ImuErrors::fill_static_lanes`].
    pub fn fill_moving_lanes(
        errors: &mut [ImuErrors],
        k0: u64,
        ideal_gyro: &[Vector3<f64>],
        ideal_accel: &[Vector3<f64>],
        outs: &mut [[&mut [f64]; 6]],
    ) {
        for c in Channel::ALL {
            let (mut lanes, mut blocks) = Self::lanes_of(errors, outs, c);
            let ideal = if c.is_gyro() { ideal_gyro } else { ideal_accel };
            ChannelErrors::fill_moving_lanes(&mut lanes, k0, ideal, &mut blocks);
        }
    }

    /// Channel `c`'s generator and block of every lane.
    fn lanes_of<'a>(
        errors: &'a mut [ImuErrors],
        outs: &'a mut [[&mut [f64]; 6]],
        c: Channel,
    ) -> (Vec<&'a mut ChannelErrors>, Vec<&'a mut [f64]>) {
        let i = c as usize;
        (
            errors.iter_mut().map(|e| &mut e.channels[i]).collect(),
            outs.iter_mut().map(|o| &mut *o[i]).collect(),
        )
    }

    /// Sensor temperature at sample k, degC.
    pub fn temperature_c(&self, k: u64) -> f64 {
        self.temperature.at(k as f64 * self.dt_s)
    }

    /// The six channel generators, for generating channels independently (e.g. in parallel):
    /// each owns its random streams, so the result does not depend on how they are scheduled.
    pub fn channels_mut(&mut self) -> &mut [ChannelErrors; 6] {
        &mut self.channels
    }

    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }
}
