//! Unit tests of the log reader.

use super::*;
use crate::csv::parse_chunk;
use crate::float::{fast_f64, number, swar_f64};

fn opts() -> ReadOptions {
    ReadOptions::default()
}

#[test]
fn reads_comments_units_and_mapping() {
    let text = b"# a comment\n# another\ngyro_x_dps,acc_z_g,other\n1.0,-1.0,5\n# mid comment\n2.0,-0.5,6\n\n3.0,0,7\n";
    let o = ReadOptions {
        rate_hz: Some(100.0),
        units: UnitOptions {
            gyro: Some(GyroUnit::DegPerS),
            accel: Some(AccelUnit::G),
            time: None,
        },
        columns: vec![
            ("gx".into(), "gyro_x_dps".into()),
            ("az".into(), "acc_z_g".into()),
        ],
        topic: None,
    };
    let log = parse_log(text, "x.csv", &o).unwrap();
    assert_eq!(log.len(), 3);
    // Unrecognised columns are skipped and listed, never analysed without a quantity and unit.
    assert_eq!(log.order_names(), vec!["gx", "az"]);
    assert_eq!(log.skipped.len(), 1);
    assert_eq!(log.skipped[0].column, "other");
    assert!((log.channel(Channel::Gx).unwrap()[1] - 2.0f64.to_radians()).abs() < 1e-15);
    assert!((log.channel(Channel::Az).unwrap()[0] + STANDARD_GRAVITY_MPS2).abs() < 1e-12);
    assert_eq!(log.rate_hz, 100.0);
    // The same without --col and without the unit options: the names say it all.
    let o = ReadOptions {
        rate_hz: Some(100.0),
        ..ReadOptions::default()
    };
    let auto = parse_log(text, "x.csv", &o).unwrap();
    assert_eq!(auto.channels, log.channels);
    assert!(auto
        .mapping_text(&Setting::name)
        .contains("gyro_x_dps -> gx (deg/s, from the name)"));
}

#[test]
fn time_columns_in_other_units_are_converted() {
    let log = parse_log(
        b"timestamp_ns,gx\n0,1\n10000000,2\n20000000,3\n",
        "x",
        &opts(),
    )
    .unwrap();
    assert!((log.rate_hz - 100.0).abs() < 1e-9);
    let o = ReadOptions {
        units: UnitOptions {
            time: Some(TimeUnit::Ms),
            ..UnitOptions::default()
        },
        ..ReadOptions::default()
    };
    let log = parse_log(b"time,gx\n0,1\n10,2\n20,3\n", "x", &o).unwrap();
    assert!((log.rate_hz - 100.0).abs() < 1e-9);
}

#[test]
fn rate_from_time_column() {
    let log = parse_log(b"t,gx\n0.0,1\n0.01,2\n0.02,3\n", "x", &opts()).unwrap();
    assert!((log.rate_hz - 100.0).abs() < 1e-9);
}

#[test]
fn errors_name_file_line_and_column() {
    let e = parse_log(b"# c\nt,gx\n0,1\n0.01,abc\n", "f.csv", &opts()).unwrap_err();
    let msg = format!("{e:#}");
    assert!(
        msg.contains("f.csv:4") && msg.contains("\"gx\"") && msg.contains("abc"),
        "{msg}"
    );
    let e = parse_log(b"t,gx\n0,1\n0.01\n", "f.csv", &opts()).unwrap_err();
    assert!(
        format!("{e:#}").contains("f.csv:3: 1 fields, expected 2"),
        "{e:#}"
    );
    let e = parse_log(b"t,gx\n0,1\n0,2\n", "f.csv", &opts()).unwrap_err();
    assert!(format!("{e:#}").contains("f.csv:3: time"), "{e:#}");
    let e = parse_log(b"gx\n1\n2\n", "f.csv", &opts()).unwrap_err();
    assert!(format!("{e:#}").contains("rate_hz HZ"), "{e:#}");
}

#[test]
fn fast_path_agrees_with_std_parser_bit_for_bit() {
    // Random doubles printed in the formats logs use, plus hand-picked edge cases.
    let mut st = 0x1234_5678_9abc_def0u64;
    let mut next = || {
        st ^= st << 13;
        st ^= st >> 7;
        st ^= st << 17;
        st
    };
    let mut texts: Vec<String> = [
        "0",
        "-0",
        "0.0",
        "1",
        "-1.5",
        "0.05",
        "-.5",
        ".",
        "-",
        "-.",
        "1234567",
        "12345678",
        "-9999999",
        "999999.9",
        ".0000001",
        "0.000001",
        "-1.",
        "12.5e1",
        "1-2",
        "1.2.3",
        "-0.35",
        "1e3",
        "1.5E-3",
        "-2.5e+10",
        "9007199254740991",
        "9007199254740993",
        "123456789012345678901",
        "1e22",
        "1e23",
        "1e-22",
        "1e-23",
        ".5",
        "5.",
        "0.1",
        "3.14159265358979",
        "00012.5000",
        "1e400",
        "4.9e-324",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for _ in 0..20_000 {
        let v = f64::from_bits(next() >> 2) * if next() % 2 == 0 { 1.0 } else { -1.0 };
        let small = (next() % 2_000_001) as f64 / 1000.0 - 1000.0;
        texts.push(format!("{v:e}"));
        texts.push(format!("{small}"));
        texts.push(format!("{:.2}", small / 10.0));
        texts.push(format!("{}", (next() % 4001) as f64 * 0.05 - 100.0));
        texts.push(format!("{:.6}", small / 7.0));
        texts.push(format!("{:.17e}", small / 3.0));
    }
    let mut swar_read = 0usize;
    for t in &texts {
        let want: Option<f64> = t.parse().ok();
        // A fast path reads a valid number whole and exactly, or declines, or reads a
        // prefix of an invalid field (the caller then finds no terminator).
        let check = |got: Option<(f64, usize)>| {
            if let Some((got, used)) = got {
                if used == t.len() {
                    assert_eq!(Some(got.to_bits()), want.map(f64::to_bits), "{t}");
                } else {
                    assert!(want.is_none(), "{t}: read {used} bytes");
                }
            }
        };
        check(fast_f64(t.as_bytes()));
        // the word-at-a-time path needs a terminator and 8 bytes after the sign
        for end in [",", "\n", "\r\n"] {
            check(number(format!("{t}{end}xxxxxxxx").as_bytes()));
            let got = swar_f64(format!("{t}{end}xxxxxxxx").as_bytes());
            swar_read += usize::from(got.is_some());
            check(got);
        }
    }
    // the short formats (most of the "{small}" and "{:.2}" texts) went the SWAR way
    assert!(swar_read > 3 * 20_000, "{swar_read}");
    // and through the chunk parser (fast or slow path per field)
    let body: String = texts
        .iter()
        .filter(|t| t.parse::<f64>().is_ok_and(f64::is_finite))
        .map(|t| format!("{t}\n"))
        .collect();
    let names = vec!["x".to_string()];
    let (_, cols) = parse_chunk(body.as_bytes(), 1, &names);
    let cols = cols.unwrap();
    for (v, t) in cols[0].iter().zip(body.lines()) {
        assert_eq!(v.to_bits(), t.parse::<f64>().unwrap().to_bits(), "{t}");
    }
}

#[test]
fn error_line_numbers_across_parallel_chunks() {
    // Many rows so the body is split into several chunks; the bad row is near the end.
    let mut s = String::from("# header comment\ngx\n");
    for i in 0..50_000 {
        if i == 43_210 {
            s.push_str("oops\n");
        } else {
            s.push_str(&format!("{}\n", i as f64 * 0.5));
        }
    }
    let o = ReadOptions {
        rate_hz: Some(1.0),
        ..opts()
    };
    let e = parse_log(s.as_bytes(), "big.csv", &o).unwrap_err();
    // line 1 comment, line 2 header, row i on line i + 3
    assert!(
        format!("{e:#}").contains(&format!("big.csv:{}:", 43_210 + 3)),
        "{e:#}"
    );
    let good = s.replace("oops", "1.0");
    let log = parse_log(good.as_bytes(), "big.csv", &o).unwrap();
    assert_eq!(log.len(), 50_000);
    assert_eq!(log.channel(Channel::Gx).unwrap()[49_999], 49_999.0 * 0.5);
}

#[test]
fn large_file_is_mapped_and_reads_as_parsed() {
    // Over 1 MiB: read_log maps the file instead of reading it; same log either way.
    let mut s = String::from("t,gx\n");
    for i in 0..120_000 {
        s.push_str(&format!(
            "{},{}\n",
            i as f64 * 0.01,
            (i % 97) as f64 * -0.05
        ));
    }
    assert!(s.len() > 1 << 20);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.csv");
    std::fs::write(&path, &s).unwrap();
    let read = read_log(&path, &opts()).unwrap();
    let parsed = parse_log(s.as_bytes(), "big.csv", &opts()).unwrap();
    assert_eq!(read.len(), 120_000);
    assert_eq!(read.channels, parsed.channels);
    assert_eq!(read.t_s, parsed.t_s);
    assert_eq!(read.channel(Channel::Gx).unwrap()[96], 96.0 * -0.05);
}

#[test]
fn comments_and_blank_lines_inside_large_chunks() {
    // Every parallel chunk holds comment, blank and irregular lines: rows stay in file
    // order with no gaps; an error deep in the file names its line.
    let mut s = String::from("t,gx\n");
    let mut want = Vec::new();
    for i in 0..60_000 {
        match i % 997 {
            5 => s.push_str("# note\n"),
            9 => s.push('\n'),
            _ => {}
        }
        let v = (i % 41) as f64 * 0.25 - 3.0;
        if i % 1013 == 7 {
            s.push_str(&format!(" {} , {v:e}\r\n", i as f64 * 0.01));
        } else {
            s.push_str(&format!("{},{v}\n", i as f64 * 0.01));
        }
        want.push(v);
    }
    let log = parse_log(s.as_bytes(), "c.csv", &opts()).unwrap();
    assert_eq!(log.channel(Channel::Gx).unwrap(), want);
    let lines: Vec<&str> = s.lines().collect();
    let bad = lines.len() - 1234;
    let broken: String = lines
        .iter()
        .enumerate()
        .map(|(k, l)| {
            if k == bad {
                "1,zz\n".to_string()
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let e = parse_log(broken.as_bytes(), "c.csv", &opts()).unwrap_err();
    assert!(
        format!("{e:#}").contains(&format!("c.csv:{}:", bad + 1)),
        "{e:#}"
    );
}

/// EuRoC / TUM-VI write their header as a comment line; the units are in brackets.
#[test]
fn euroc_style_comment_header_with_units_in_brackets() {
    let text = b"#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n\
1403636579758555392,-0.099134701513277898,0.14730578886832138,0.02722713633111154,8.1476917083333333,-0.37592158333333331,-2.4026292499999999\n\
1403636579763555584,-0.099134701513277898,0.14032447186034408,0.029321531433504733,8.033280791666666,-0.40861041666666664,-2.4026292499999999\n\
1403636579768555520,-0.098436569812480182,0.12426744274199649,0.02931365027581343,7.8861057916666666,-0.42495483333333334,-2.4353180833333332\n";
    let log = parse_log(text, "data.csv", &opts()).unwrap();
    assert_eq!(log.len(), 3);
    assert!((log.rate_hz - 200.0).abs() < 0.1, "{}", log.rate_hz);
    assert_eq!(log.order_names(), vec!["gx", "gy", "gz", "ax", "ay", "az"]);
    assert_eq!(
        log.channel(Channel::Ax).unwrap()[0],
        "8.1476917083333333".parse::<f64>().unwrap()
    );
    assert!(
        log.mapping_text(&Setting::name)
            .contains("timestamp [ns] -> t (ns, from the name)"),
        "{}",
        log.mapping_text(&Setting::name)
    );
    assert!(
        log.mapping_text(&Setting::name)
            .contains("w_RS_S_x [rad s^-1] -> gx (rad/s"),
        "{}",
        log.mapping_text(&Setting::name)
    );
}

/// `rostopic echo -p` CSVs: `%time` in ns, `field.` prefixes, text columns that are skipped.
#[test]
fn rostopic_csv_with_text_columns() {
    let text = b"%time,field.header.seq,field.header.stamp,field.header.frame_id,field.angular_velocity.x,field.angular_velocity.y,field.angular_velocity.z,field.angular_velocity_covariance0,field.linear_acceleration.x,field.linear_acceleration.y,field.linear_acceleration.z\n\
1000000000,1,1000000000,imu_link,0.1,0.2,0.3,0.0,1,2,3\n\
1010000000,2,1010000000,imu_link,0.1,0.2,0.3,0.0,1,2,3\n\
1020000000,3,1020000000,imu_link,0.1,0.2,0.3,0.0,1,2,3\n";
    let log = parse_log(text, "echo.csv", &opts())
        .unwrap_err()
        .to_string();
    // angular_velocity.x has no unit in its name: the option is needed (REP 103 says rad/s, but
    // a CSV column is not a message).
    assert!(
        log.contains("units.gyro") && log.contains("field.angular_velocity.x"),
        "{log}"
    );
    let o = ReadOptions {
        units: UnitOptions {
            gyro: Some(GyroUnit::RadPerS),
            accel: Some(AccelUnit::MPerS2),
            time: None,
        },
        ..ReadOptions::default()
    };
    let log = parse_log(text, "echo.csv", &o).unwrap();
    assert!((log.rate_hz - 100.0).abs() < 1e-6);
    assert_eq!(log.channel(Channel::Gz).unwrap(), vec![0.3; 3]);
    let skipped: Vec<&str> = log.skipped.iter().map(|s| s.column.as_str()).collect();
    assert!(
        skipped.contains(&"field.header.frame_id")
            && skipped.contains(&"field.angular_velocity_covariance0"),
        "{skipped:?}"
    );
}
