//! `spec --out`: one SVG per quantity with every sensor's drift beside the requirements on it:
//! heading and horizontal position (the simulated RMS of each sensor, its closed-form law dashed),
//! and any other quantity a requirement names; each requirement as its threshold (a black marker
//! at its time) and each sensor's value of its statistic.

use crate::plot::{LogLogPlot, Series, PALETTE};
use montecarlo::nav_quantity::NavQuantity;
use montecarlo::requirement::RequirementResult;
use montecarlo::spec::DriftRow;

/// One sensor's part of the plots.
pub struct SensorDrift<'a> {
    pub name: &'a str,
    pub drift: &'a [DriftRow],
    pub requirements: &'a [RequirementResult],
}

/// Display scale and unit of a quantity (JSON name): degrees for angles, SI otherwise.
fn scale_unit(name: &str) -> (f64, &'static str) {
    if name.ends_with("_rad") {
        (180.0 / std::f64::consts::PI, "deg")
    } else if name.ends_with("_mps") {
        (1.0, "m/s")
    } else {
        (1.0, "m")
    }
}

/// (file name, SVG) per quantity: heading and horizontal position always, and each other
/// quantity a requirement names.
pub fn plots(sensors: &[SensorDrift]) -> Vec<(String, String)> {
    let mut names: Vec<&'static str> =
        vec![NavQuantity::Yaw.name(), NavQuantity::PosHorizontal.name()];
    for s in sensors {
        for r in s.requirements {
            if !names.contains(&r.quantity) {
                names.push(r.quantity);
            }
        }
    }
    names
        .into_iter()
        .map(|name| {
            let label = NavQuantity::from_name(name).map_or(name, |q| q.label());
            (format!("spec_{label}.svg"), plot(name, sensors).to_svg())
        })
        .collect()
}

fn plot(name: &str, sensors: &[SensorDrift]) -> LogLogPlot {
    let (scale, unit) = scale_unit(name);
    let mut series = Vec::new();
    for (i, s) in sensors.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let t: Vec<f64> = s.drift.iter().map(|d| d.t_s).collect();
        let curve = |f: &dyn Fn(&DriftRow) -> Option<f64>| -> Vec<f64> {
            s.drift
                .iter()
                .map(|d| f(d).map_or(f64::NAN, |v| v * scale))
                .collect()
        };
        let (sim, law): (Vec<f64>, Vec<f64>) = if name == NavQuantity::Yaw.name() {
            (
                curve(&|d| Some(d.heading_rms_sim_rad)),
                curve(&|d| d.heading_rms_law_rad),
            )
        } else if name == NavQuantity::PosHorizontal.name() {
            (
                curve(&|d| Some(d.horizontal_rms_sim_m)),
                curve(&|d| d.horizontal_rms_law_m),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        if !sim.is_empty() {
            series.push(Series::new(
                &format!("{} RMS", s.name),
                t.clone(),
                sim,
                color,
            ));
            series.push(Series::dashed(&format!("{} law", s.name), t, law, color));
        }
        let reqs: Vec<&RequirementResult> = s
            .requirements
            .iter()
            .filter(|r| r.quantity == name)
            .collect();
        if let Some(first) = reqs.first() {
            series.push(Series {
                dashed: false,
                ..Series::new(
                    &format!("{} {} at the requirements", s.name, first.statistic.name()),
                    reqs.iter().map(|r| r.t_s).collect(),
                    reqs.iter()
                        .map(|r| r.value.map_or(f64::NAN, |v| v * scale))
                        .collect(),
                    color,
                )
            });
        }
    }
    // The thresholds, once per requirement text (every sensor answers the same ones).
    let mut thresholds: Vec<(f64, f64)> = Vec::new();
    for r in sensors.iter().flat_map(|s| s.requirements.iter()) {
        if r.quantity == name && !thresholds.contains(&(r.t_s, r.threshold)) {
            thresholds.push((r.t_s, r.threshold));
        }
    }
    if !thresholds.is_empty() {
        series.push(Series::new(
            "requirement threshold",
            thresholds.iter().map(|t| t.0).collect(),
            thresholds.iter().map(|t| t.1 * scale).collect(),
            "#000000",
        ));
    }
    let label: &str = match NavQuantity::from_name(name) {
        Some(q) => q.label(),
        None => name,
    };
    LogLogPlot {
        title: format!("{}: sensors side by side", crate::fmt::quantity_label(label)),
        subtitle: "simulated RMS (solid) and closed-form law (dashed), static and level; requirement values as markers".into(),
        notes: Vec::new(),
        x_label: "t (s)".into(),
        y_label: format!("{} ({unit})", crate::fmt::quantity_label(label)),
        series,
        bands: Vec::new(),
    }
}
