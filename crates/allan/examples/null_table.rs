//! Prints one family of the null thresholds' table (`allan::null_table`) as Rust source:
//! `null_table <adev|oadev|totdev> <octave|decade> <replicates> <largest n>`. Every segment whose
//! last length is at most the largest n gets its four nodes, each simulated with `replicates`
//! null logs through the whole analysis. scripts/null_table.sh runs it for every family and
//! writes crates/allan/src/null_table_data.rs.

use allan::null::{null_statistics, tail_of};
use allan::null_table::{nodes, Grid};
use allan::{Estimator, Options};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: null_table <adev|oadev|totdev> <octave|decade> <replicates> <largest n>";
    if args.len() != 4 {
        eprintln!("{usage}");
        std::process::exit(2);
    }
    let est = Estimator::from_name(&args[0]).expect(usage);
    let grid = match args[1].as_str() {
        "octave" => Grid::Octave,
        "decade" => Grid::Decade,
        _ => panic!("{usage}"),
    };
    let replicates: usize = args[2].parse().expect(usage);
    let cap: usize = args[3].parse().expect(usage);
    let ratio = est.stable32_stop_ratio();
    let factors = grid.factors();
    let opts = Options::default();
    let variant = |e: Estimator| format!("{e:?}");
    println!(
        "    Family {{\n        est: Estimator::{},\n        grid: Grid::{:?},\n        replicates: {replicates},\n        rows: &[",
        variant(est),
        grid
    );
    let t0 = Instant::now();
    for s in 0.. {
        if ratio * factors[s + 1] - 1 > cap {
            break;
        }
        for n in nodes(s, ratio, &factors) {
            let stats = null_statistics(
                n,
                0.01,
                est,
                &grid.tau_grid(),
                &opts,
                replicates,
                &|_, _| {},
            );
            let (start, scale) = tail_of(&stats).expect("at least 20 replicates");
            println!("            Row {{ n: {n}, start: {start:?}, scale: {scale:?} }},");
            eprintln!(
                "{} {:?} segment {s} n {n}: {:.1} s",
                est.name(),
                grid,
                t0.elapsed().as_secs_f64()
            );
        }
    }
    println!("        ],\n    }},");
}
