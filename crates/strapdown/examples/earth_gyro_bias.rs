//! The horizontal position error of a constant gyro bias alone on the round, rotating Earth: an
//! ideal static, level, north-facing IMU with and without the bias, integrated by
//! `Strapdown::on_earth` (accurate scheme), the difference of the two solutions (as
//! scripts/earth_vs_gnss_ins_sim.py does with gnss-ins-sim). Prints one JSON line.
//!
//! `earth_gyro_bias LAT_DEG RATE_HZ BIAS_X_DEG_H T1,T2,... free|held`

use strapdown::earth::Place;
use strapdown::{Attitude, BodyVector, NavState, RoundEarth, Scheme, Strapdown, Vertical};

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: earth_gyro_bias LAT_DEG RATE_HZ BIAS_X_DEG_H T1,T2,... free|held";
    if a.len() != 5 {
        eprintln!("{usage}");
        std::process::exit(2);
    }
    let num = |s: &str| -> f64 { s.parse().unwrap_or_else(|_| panic!("{usage}")) };
    let (lat, rate, bias_deg_h) = (num(&a[0]), num(&a[1]), num(&a[2]));
    let times: Vec<f64> = a[3].split(',').map(num).collect();
    let vertical = match a[4].as_str() {
        "free" => Vertical::Free,
        "held" => Vertical::Held,
        _ => panic!("{usage}"),
    };
    let earth = RoundEarth {
        vertical,
        ..RoundEarth::at(Place::from_deg(lat, 0.0, 0.0))
    };
    let att = Attitude::identity();
    let dt = 1.0 / rate;
    let (w, f) = earth.static_imu(&att);
    let biased = BodyVector::new(w.0.x + (bias_deg_h / 3600.0).to_radians(), w.0.y, w.0.z);
    let mut ideal = Strapdown::on_earth(Scheme::Accurate, NavState::default(), earth);
    let mut with_bias = Strapdown::on_earth(Scheme::Accurate, NavState::default(), earth);
    ideal.set_previous_gyro(&w, dt);
    with_bias.set_previous_gyro(&biased, dt);
    let steps = (times.last().copied().unwrap_or(0.0) * rate).round() as usize;
    let mut out = Vec::new();
    for i in 1..=steps {
        ideal.step(&w, &f, dt);
        with_bias.step(&biased, &f, dt);
        let t = i as f64 * dt;
        if times.iter().any(|s| (s - t).abs() < dt / 2.0) {
            let d = with_bias.state().position.0 - ideal.state().position.0;
            out.push(format!(
                "{{\"t_s\": {t}, \"north_m\": {}, \"east_m\": {}, \"down_m\": {}, \"horizontal_m\": {}}}",
                d.x,
                d.y,
                d.z,
                d.x.hypot(d.y)
            ));
        }
    }
    println!("[{}]", out.join(", "));
}
