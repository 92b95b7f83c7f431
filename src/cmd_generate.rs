//! `imudrift generate`: a synthetic static, level IMU log from a sensor model.
//!
//! Columns `t,gx,gy,gz,ax,ay,az,temp` in SI (s, rad/s, m/s^2, degC), gravity on the accelerometers
//! (a level IMU in body FRD reads specific force (0, 0, -g)). The log is generated and written in
//! blocks, so memory does not grow with its length; each channel owns its random streams, so channels
//! are generated in parallel and the bytes do not depend on the thread count. The file appears only
//! when complete (src/output.rs).

use crate::cli::request_error;
use crate::output;
use anyhow::{bail, Result};
use noise::{Channel, ImuErrors, StaticLevel};
use rayon::prelude::*;
use request::generate::{GeneratePlan, GenerateRequest};
use request::SensorSource;
use std::io::Write;
use std::path::PathBuf;

/// Samples generated per block (per channel); bounds memory at ~0.8 MB of samples plus their text.
const BLOCK_SAMPLES: usize = 1 << 15;
/// Rows formatted per parallel task.
const FORMAT_ROWS: usize = 4096;

#[derive(clap::Args)]
pub struct Args {
    /// Sensor config (TOML), e.g. configs/sensors/mtx.toml
    pub sensor: PathBuf,
    /// Log length: seconds, or a value with a unit ("12 h", "30 min")
    #[arg(long, value_parser = crate::cli::duration_s)]
    pub duration: f64,
    /// Sample rate in Hz
    #[arg(long)]
    pub rate: f64,
    /// Output CSV file
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Master seed (written into the log's header)
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Run index: which run's per-run draws (turn-on bias, initial states) to use
    #[arg(long, default_value_t = 0)]
    pub run: u64,
    /// Only these terms, e.g. gyro.white_noise,accel.constant_bias (or `white_noise`, `gyro`)
    #[arg(long, value_delimiter = ',', value_parser = noise::TermSelector::parse)]
    pub only: Option<Vec<noise::TermSelector>>,
    /// All terms but these, same syntax as --only
    #[arg(long, value_delimiter = ',', value_parser = noise::TermSelector::parse)]
    pub without: Vec<noise::TermSelector>,
    /// Worker threads (default: all cores); the output does not depend on it
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print a JSON summary on stdout
    #[arg(long)]
    pub json: bool,
}

/// Upper estimate of one CSV row (t, six channels, temp; shortest round-trip numbers of up to
/// 24 characters each), bytes.
const BYTES_PER_ROW: f64 = 8.0 * 25.0;

/// The request of the command line, checked (`request::generate`), and the checks only a file
/// output has: the log must fit where it goes.
fn plan(args: &Args) -> Result<GeneratePlan> {
    let req = GenerateRequest {
        sensor: SensorSource::Path(args.sensor.clone()),
        duration_s: args.duration,
        rate_hz: args.rate,
        seed: args.seed,
        run: args.run,
        only: args.only.clone(),
        without: args.without.clone(),
        output: Some(args.output.display().to_string()),
    };
    let plan = req.validate().map_err(request_error)?;
    let samples = plan.samples as f64;
    // Refuse before writing rather than fill the disk.
    if std::fs::metadata(&args.output).map_or(true, |m| m.is_file()) {
        let dir = match args.output.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => std::path::PathBuf::from("."),
        };
        let need = samples * BYTES_PER_ROW;
        if let Ok(free) = fs4::available_space(&dir) {
            if need > free as f64 {
                bail!(
                    "-o {}: {samples:.3e} samples are about {} of CSV and {} has {} free: generate a shorter log, at a lower --rate, or on another disk",
                    args.output.display(),
                    crate::fmt::bytes(need),
                    dir.display(),
                    crate::fmt::bytes(free as f64)
                );
            }
        }
    }
    // An --only list that keeps none of the model's terms leaves an ideal IMU: allowed, but say so.
    if plan.only_keeps_nothing {
        tell!(
            "note: {} has none of the --only terms; the log is an ideal IMU",
            args.sensor.display()
        );
    }
    crate::model_notes::print(&plan.model, None);
    Ok(plan)
}

pub fn run(args: Args) -> Result<()> {
    crate::output::note_inputs([&args.sensor]);
    crate::output::refuse_input_as_output("-o", &args.output)?;
    let plan = plan(&args)?;
    let pool = crate::cli::pool(args.threads)?;
    let progress = crate::progress::Progress::new("generate", "samples", plan.samples);
    let started = std::time::Instant::now();
    // Atomic for files; devices and FIFOs (/dev/null) are written directly (output.rs).
    output::write_atomic(&args.output, |w| {
        write_log(w, &plan, &args, &pool, &progress)
    })?;
    progress.finish();
    let elapsed_s = started.elapsed().as_secs_f64();
    tell!(
        "wrote {} samples ({} at {}) of {} to {} in {elapsed_s:.2} s (seed {}, run {})",
        plan.samples,
        crate::fmt::time(plan.samples as f64 / plan.rate_hz),
        crate::fmt::rate(plan.rate_hz),
        plan.model.name,
        args.output.display(),
        args.seed,
        args.run
    );
    if args.json {
        let doc = serde_json::json!({
            "sensor": plan.model.name,
            "config": args.sensor.display().to_string(),
            "output": args.output.display().to_string(),
            "seed": args.seed,
            "run": args.run,
            "rate_hz": plan.rate_hz,
            "samples": plan.samples,
            "duration_s": plan.samples as f64 / plan.rate_hz,
            "terms": crate::cli::describe_filter(&plan.filter),
            "elapsed_s": elapsed_s,
        });
        crate::output::print_stdout(&format!("{doc}\n"))?;
    }
    Ok(())
}

fn write_log(
    w: &mut dyn Write,
    plan: &GeneratePlan,
    args: &Args,
    pool: &rayon::ThreadPool,
    progress: &crate::progress::Progress,
) -> Result<()> {
    let dt_s = 1.0 / plan.rate_hz;
    writeln!(
        w,
        "# imudrift generate: sensor \"{}\" ({}), seed {}, run {}, rate {} Hz, {} samples{}",
        plan.model.name,
        args.sensor.display(),
        args.seed,
        args.run,
        plan.rate_hz,
        plan.samples,
        if plan.filter.is_all() {
            String::new()
        } else {
            format!(", terms {}", crate::cli::describe_filter(&plan.filter))
        }
    )?;
    writeln!(
        w,
        "# static level IMU, body FRD: gyro rad/s, accel m/s^2 (specific force, gravity on az), temp degC"
    )?;
    writeln!(w, "t,{},temp", Channel::ALL.map(Channel::name).join(","))?;

    let mut errors = ImuErrors::new(&plan.model, dt_s, args.seed, args.run);
    let ideal = StaticLevel::STANDARD.inputs();
    // A producer thread generates and formats block after block (both in parallel on the pool) while
    // this thread writes the previous one; at most two formatted blocks wait in the channel.
    // A block with a value that is not finite (a model whose values overflow) ends the log with
    // an error instead of writing `inf` or `NaN` into it.
    let (tx, rx) = std::sync::mpsc::sync_channel::<Result<(u64, Vec<Vec<u8>>), String>>(2);
    std::thread::scope(|scope| {
        scope.spawn(move || {
            let mut block: Vec<Vec<f64>> = vec![vec![0.0; BLOCK_SAMPLES]; 6];
            let mut k0 = 0u64;
            while k0 < plan.samples {
                let n = (plan.samples - k0).min(BLOCK_SAMPLES as u64) as usize;
                pool.install(|| {
                    errors
                        .channels_mut()
                        .par_iter_mut()
                        .zip(block.par_iter_mut())
                        .enumerate()
                        .for_each(|(c, (channel, out))| {
                            channel.fill_static(k0, &ideal[Channel::ALL[c]], &mut out[..n]);
                        })
                });
                // The one rule of generated values (`request::generate`), as Python applies it.
                let channels = Channel::ALL.iter().zip(&block).map(|(&c, v)| (c, &v[..n]));
                if let Err(e) = GeneratePlan::check_values(k0, channels) {
                    let _ = tx.send(Err(e.render(&crate::cli::flag)));
                    return;
                }
                let texts: Vec<Vec<u8>> = pool.install(|| {
                    (0..n)
                        .step_by(FORMAT_ROWS)
                        .collect::<Vec<_>>()
                        .into_par_iter()
                        .map(|start| {
                            let end = (start + FORMAT_ROWS).min(n);
                            format_rows(&block, &errors, k0, start..end, plan.rate_hz)
                        })
                        .collect()
                });
                k0 += n as u64;
                // The writer hung up (a write failed): stop generating.
                if tx.send(Ok((k0, texts))).is_err() {
                    return;
                }
            }
        });
        for item in rx {
            let (k_done, texts) = item.map_err(|e| anyhow::anyhow!("{e}"))?;
            for t in texts {
                w.write_all(&t)?;
            }
            progress.set(k_done);
        }
        Ok(())
    })
}

/// CSV rows for block rows `range`; floats in shortest round-trip form (ryu).
fn format_rows(
    block: &[Vec<f64>],
    errors: &ImuErrors,
    k0: u64,
    range: std::ops::Range<usize>,
    rate_hz: f64,
) -> Vec<u8> {
    let mut text = Vec::with_capacity(range.len() * 200);
    let mut buf = ryu::Buffer::new();
    // The temperature is often constant or slow: format it only when it changes.
    let mut temp_bits = None;
    let mut temp_text = Vec::new();
    for i in range {
        let k = k0 + i as u64;
        // t = k / rate from the integer index (docs/architecture.md: never t += dt).
        text.extend_from_slice(buf.format(k as f64 / rate_hz).as_bytes());
        for channel in block {
            text.push(b',');
            text.extend_from_slice(buf.format(channel[i]).as_bytes());
        }
        let temp = errors.temperature_c(k);
        if temp_bits != Some(temp.to_bits()) {
            temp_bits = Some(temp.to_bits());
            temp_text.clear();
            temp_text.push(b',');
            temp_text.extend_from_slice(buf.format(temp).as_bytes());
            temp_text.push(b'\n');
        }
        text.extend_from_slice(&temp_text);
    }
    text
}
