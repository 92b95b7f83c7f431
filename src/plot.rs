//! A small dependency-free SVG writer for log-log plots: line/marker series, shaded bands
//! (confidence intervals, Monte Carlo envelopes) and a legend. Used by `allan`, `diagnose`,
//! `drift`, `simulate` and `spec`.
//!
//! Every text stays inside the canvas: titles, subtitles and notes are wrapped to its width by a
//! conservative width estimate ([`text_width`]), the canvas grows by the lines they take, and the
//! legend goes to the corner of the plot area where it covers the fewest data points.

use std::fmt::Write;

/// A line or marker series.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub color: String,
    pub dashed: bool,
    pub markers: bool,
}

impl Series {
    /// Solid line with markers.
    pub fn new(name: &str, x: Vec<f64>, y: Vec<f64>, color: &str) -> Series {
        Series {
            name: name.into(),
            x,
            y,
            color: color.into(),
            dashed: false,
            markers: true,
        }
    }

    /// Dashed line without markers (for model terms).
    pub fn dashed(name: &str, x: Vec<f64>, y: Vec<f64>, color: &str) -> Series {
        Series {
            name: name.into(),
            x,
            y,
            color: color.into(),
            dashed: true,
            markers: false,
        }
    }
}

/// A shaded band between `lo` and `hi`.
#[derive(Clone, Debug)]
pub struct Band {
    pub name: String,
    pub x: Vec<f64>,
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
    pub color: String,
}

/// A log-log plot.
#[derive(Clone, Debug, Default)]
pub struct LogLogPlot {
    pub title: String,
    /// A second, smaller title line (the protocol, the source), wrapped like the title.
    pub subtitle: String,
    /// Lines written under the plot (readings, bounds), wrapped to the width.
    pub notes: Vec<String>,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    pub bands: Vec<Band>,
}

/// A palette of distinguishable colours.
pub const PALETTE: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
];

const W: f64 = 820.0;
/// Height of the plot area plus the axis labels; the canvas adds the title and note lines.
const BASE_H: f64 = 510.0;
const LEFT: f64 = 90.0;
const RIGHT: f64 = 30.0;
const BOTTOM: f64 = 70.0;
const TITLE_SIZE: f64 = 16.0;
const TEXT_SIZE: f64 = 12.0;
/// Margin kept free at each side of a wrapped line.
const MARGIN: f64 = 10.0;

/// A conservative width (px) of `text` in a sans-serif font of `size` px: per character the
/// widest of DejaVu Sans / Arial / Helvetica in its class, rounded up (digits and lower case
/// 0.65 em, upper case 0.8 em, `m` `w` `M` `W` and non-ASCII 1.0 em, space and narrow marks
/// 0.42 em), so a real renderer draws the text no wider.
pub fn text_width(text: &str, size: f64) -> f64 {
    text.chars()
        .map(|c| match c {
            'm' | 'w' | 'M' | 'W' => 1.0,
            'i' | 'j' | 'l' | 't' | 'f' | 'r' | '.' | ',' | ':' | ';' | '\'' | '!' | '|' | ' '
            | '(' | ')' | '[' | ']' => 0.42,
            c if c.is_ascii_uppercase() => 0.8,
            c if c.is_ascii() => 0.65,
            _ => 1.0,
        })
        .sum::<f64>()
        * size
}

/// `text` broken at spaces into lines no wider than `width` px at `size` (a word longer than
/// the width is cut into pieces).
pub fn wrap(text: &str, size: f64, width: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        let trial = if line.is_empty() {
            word.to_string()
        } else {
            format!("{line} {word}")
        };
        if text_width(&trial, size) <= width || line.is_empty() && word.is_empty() {
            line = trial;
            continue;
        }
        if !line.is_empty() {
            lines.push(std::mem::take(&mut line));
        }
        let mut piece = String::new();
        for c in word.chars() {
            piece.push(c);
            if text_width(&piece, size) > width {
                piece.pop();
                lines.push(std::mem::take(&mut piece));
                piece.push(c);
            }
        }
        line = piece;
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// The canvas's text lines and the plot area's place.
struct Layout {
    title: Vec<String>,
    subtitle: Vec<String>,
    notes: Vec<String>,
    top: f64,
    height: f64,
}

impl LogLogPlot {
    /// The same plot with its y values (an Allan deviation in `si_unit`, rad/s or m/s^2) in the
    /// unit spec sheets use for it (deg/h, ug), the label saying which and how it relates to SI.
    pub fn in_spec_sheet_units(mut self, quantity: &str, si_unit: &str) -> LogLogPlot {
        let (k, unit) = crate::fmt::allan_units(si_unit)[0].clone();
        if k != 1.0 {
            for s in &mut self.series {
                s.y.iter_mut().for_each(|v| *v *= k);
            }
            for b in &mut self.bands {
                b.lo.iter_mut().for_each(|v| *v *= k);
                b.hi.iter_mut().for_each(|v| *v *= k);
            }
            self.y_label = format!(
                "{quantity} ({unit}; 1 {unit} = {} {si_unit})",
                crate::fmt::sig(1.0 / k, 4)
            );
        } else {
            self.y_label = format!("{quantity} ({si_unit})");
        }
        self
    }

    /// The title, subtitle and note lines wrapped to the canvas, and the heights they leave.
    fn layout(&self) -> Layout {
        let width = W - 2.0 * MARGIN;
        let title = wrap(&self.title, TITLE_SIZE, width);
        let subtitle = if self.subtitle.is_empty() {
            Vec::new()
        } else {
            wrap(&self.subtitle, TEXT_SIZE, width)
        };
        let notes: Vec<String> = self
            .notes
            .iter()
            .flat_map(|n| wrap(n, TEXT_SIZE, width))
            .collect();
        let top = 12.0 + 20.0 * title.len() as f64 + 16.0 * subtitle.len() as f64 + 12.0;
        let height = top + BASE_H - 50.0 + 16.0 * notes.len() as f64 + 6.0;
        Layout {
            title,
            subtitle,
            notes,
            top,
            height,
        }
    }

    /// Render to an SVG document. Non-positive and non-finite values are skipped.
    pub fn to_svg(&self) -> String {
        let layout = self.layout();
        let frame = self.frame(&layout);
        let h = layout.height;
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{h}" viewBox="0 0 {W} {h}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(s, r#"<rect width="{W}" height="{h}" fill="white"/>"#);
        let mut y = 12.0;
        for line in &layout.title {
            y += 20.0;
            let _ = writeln!(
                s,
                r#"<text x="{}" y="{y}" text-anchor="middle" font-size="16">{}</text>"#,
                W / 2.0,
                esc(line)
            );
        }
        for line in &layout.subtitle {
            y += 16.0;
            let _ = writeln!(
                s,
                r#"<text x="{}" y="{y}" text-anchor="middle">{}</text>"#,
                W / 2.0,
                esc(line)
            );
        }
        frame.write_grid(&mut s);
        self.write_axes(&mut s, &frame);
        self.write_bands(&mut s, &frame);
        self.write_series(&mut s, &frame);
        self.write_legend(&mut s, &frame);
        let mut y = frame.top + frame.ph + BOTTOM - 4.0;
        for line in &layout.notes {
            y += 16.0;
            let _ = writeln!(s, r#"<text x="{MARGIN}" y="{y}">{}</text>"#, esc(line));
        }
        s.push_str("</svg>\n");
        s
    }

    /// The decades the plotted values span, on both axes.
    fn frame(&self, layout: &Layout) -> Frame {
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        for s in &self.series {
            for (&x, &y) in s.x.iter().zip(&s.y) {
                if plottable(x) && plottable(y) {
                    xs.push(x);
                    ys.push(y);
                }
            }
        }
        for b in &self.bands {
            for ((&x, &lo), &hi) in b.x.iter().zip(&b.lo).zip(&b.hi) {
                if plottable(x) && plottable(lo) && plottable(hi) {
                    xs.extend([x, x]);
                    ys.extend([lo, hi]);
                }
            }
        }
        let range = |v: &[f64]| -> (f64, f64) {
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if !lo.is_finite() {
                return (0.0, 1.0);
            }
            let (l, h) = (lo.log10().floor(), hi.log10().ceil());
            if h > l {
                (l, h)
            } else {
                (l, l + 1.0)
            }
        };
        let (x0, x1) = range(&xs);
        let (y0, y1) = range(&ys);
        Frame {
            x0,
            x1,
            y0,
            y1,
            top: layout.top,
            pw: W - LEFT - RIGHT,
            ph: BASE_H - 50.0 - BOTTOM,
        }
    }

    /// The plot area's border and the axis labels.
    fn write_axes(&self, s: &mut String, f: &Frame) {
        let (pw, ph, top) = (f.pw, f.ph, f.top);
        let _ = writeln!(
            s,
            r#"<rect x="{LEFT}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.2}" y="{:.2}" text-anchor="middle">{}</text>"#,
            LEFT + pw / 2.0,
            top + ph + BOTTOM - 20.0,
            esc(&self.x_label)
        );
        // The y label runs along the plot's height: shortened with an ellipsis if longer.
        let mut label = self.y_label.clone();
        if text_width(&label, TEXT_SIZE) > ph {
            while !label.is_empty() && text_width(&format!("{label}…"), TEXT_SIZE) > ph {
                label.pop();
            }
            label.push('…');
        }
        let _ = writeln!(
            s,
            r#"<text x="20" y="{:.2}" text-anchor="middle" transform="rotate(-90 20 {:.2})">{}</text>"#,
            top + ph / 2.0,
            top + ph / 2.0,
            esc(&label)
        );
    }

    /// Each band as a closed shaded path (upper edge left to right, lower edge back).
    fn write_bands(&self, s: &mut String, f: &Frame) {
        for b in &self.bands {
            let pts: Vec<(f64, f64, f64)> =
                b.x.iter()
                    .zip(&b.lo)
                    .zip(&b.hi)
                    .filter(|((x, lo), hi)| plottable(**x) && plottable(**lo) && plottable(**hi))
                    .map(|((x, lo), hi)| (*x, *lo, *hi))
                    .collect();
            if pts.is_empty() {
                continue;
            }
            let mut d = String::new();
            for (i, (x, _, hi)) in pts.iter().enumerate() {
                let _ = write!(
                    d,
                    "{}{:.2},{:.2} ",
                    if i == 0 { "M" } else { "L" },
                    f.px(*x),
                    f.py(*hi)
                );
            }
            for (x, lo, _) in pts.iter().rev() {
                let _ = write!(d, "L{:.2},{:.2} ", f.px(*x), f.py(*lo));
            }
            let _ = writeln!(
                s,
                r#"<path d="{d}Z" fill="{}" fill-opacity="0.2" stroke="none"/>"#,
                b.color
            );
        }
    }

    /// Each series as a path, with markers if it has them.
    fn write_series(&self, s: &mut String, f: &Frame) {
        for ser in &self.series {
            let pts: Vec<(f64, f64)> = ser
                .x
                .iter()
                .zip(&ser.y)
                .filter(|(x, y)| plottable(**x) && plottable(**y))
                .map(|(x, y)| (f.px(*x), f.py(*y)))
                .collect();
            if pts.is_empty() {
                continue;
            }
            let mut d = String::new();
            for (i, (x, y)) in pts.iter().enumerate() {
                let _ = write!(d, "{}{x:.2},{y:.2} ", if i == 0 { "M" } else { "L" });
            }
            let _ = writeln!(
                s,
                r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1.6"{}/>"#,
                ser.color,
                ser.dash_attribute()
            );
            if ser.markers {
                for (x, y) in &pts {
                    let _ = writeln!(
                        s,
                        r#"<circle cx="{x:.2}" cy="{y:.2}" r="2.8" fill="{}"/>"#,
                        ser.color
                    );
                }
            }
        }
    }

    /// The legend's size (px): wide enough for its longest name.
    fn legend_size(&self) -> (f64, f64) {
        let names = self
            .bands
            .iter()
            .map(|b| b.name.as_str())
            .chain(self.series.iter().map(|s| s.name.as_str()));
        let longest = names
            .map(|n| text_width(n, TEXT_SIZE))
            .fold(0.0f64, f64::max);
        let entries = self.bands.len() + self.series.len();
        (longest + 48.0, entries as f64 * 18.0 + 8.0)
    }

    /// The legend's top-left corner: of the plot area's four corners, the one whose box covers
    /// the fewest plotted points (series points and band edges, and the midpoints between
    /// neighbours); top right on a tie.
    fn legend_place(&self, f: &Frame, (lw, lh): (f64, f64)) -> (f64, f64) {
        let mut pts: Vec<(f64, f64)> = Vec::new();
        let mut add = |x: &[f64], y: &[f64]| {
            let p: Vec<(f64, f64)> = x
                .iter()
                .zip(y)
                .filter(|(x, y)| plottable(**x) && plottable(**y))
                .map(|(x, y)| (f.px(*x), f.py(*y)))
                .collect();
            for w in p.windows(2) {
                pts.push(((w[0].0 + w[1].0) / 2.0, (w[0].1 + w[1].1) / 2.0));
            }
            pts.extend(p);
        };
        for ser in &self.series {
            add(&ser.x, &ser.y);
        }
        for b in &self.bands {
            add(&b.x, &b.lo);
            add(&b.x, &b.hi);
        }
        let (right, bottom) = (LEFT + f.pw - lw - 8.0, f.top + f.ph - lh - 8.0);
        let corners = [
            (right, f.top + 8.0),
            (LEFT + 8.0, f.top + 8.0),
            (right, bottom),
            (LEFT + 8.0, bottom),
        ];
        let covered = |(x, y): (f64, f64)| {
            pts.iter()
                .filter(|(px, py)| *px >= x && *px <= x + lw && *py >= y && *py <= y + lh)
                .count()
        };
        corners
            .into_iter()
            .min_by_key(|c| covered(*c))
            .unwrap_or(corners[0])
    }

    /// The legend, in the emptiest corner: bands first, then series.
    fn write_legend(&self, s: &mut String, f: &Frame) {
        let entries = self.bands.len() + self.series.len();
        if entries == 0 {
            return;
        }
        let (lw, lh) = self.legend_size();
        let (lx, ly) = self.legend_place(f, (lw, lh));
        let _ = writeln!(
            s,
            r##"<rect x="{lx:.2}" y="{ly:.2}" width="{lw:.2}" height="{lh:.2}" fill="white" fill-opacity="0.85" stroke="#999999"/>"##
        );
        let label = |s: &mut String, y: f64, name: &str| {
            let _ = writeln!(
                s,
                r#"<text x="{:.2}" y="{:.2}">{}</text>"#,
                lx + 40.0,
                y + 1.0,
                esc(name)
            );
        };
        let mut row = 0.0;
        for b in &self.bands {
            let y = ly + 14.0 + row * 18.0;
            let _ = writeln!(
                s,
                r#"<rect x="{:.2}" y="{:.2}" width="24" height="10" fill="{}" fill-opacity="0.3"/>"#,
                lx + 8.0,
                y - 8.0,
                b.color
            );
            label(s, y, &b.name);
            row += 1.0;
        }
        for ser in &self.series {
            let y = ly + 14.0 + row * 18.0;
            let _ = writeln!(
                s,
                r#"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="{}" stroke-width="2"{}/>"#,
                lx + 8.0,
                y - 3.0,
                lx + 32.0,
                y - 3.0,
                ser.color,
                ser.dash_attribute()
            );
            label(s, y, &ser.name);
            row += 1.0;
        }
    }
}

impl Series {
    /// The SVG attribute that dashes the line, if it is dashed.
    fn dash_attribute(&self) -> &'static str {
        if self.dashed {
            r#" stroke-dasharray="6,4""#
        } else {
            ""
        }
    }
}

/// A value a log-log plot can show.
fn plottable(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// The plot area: the decades shown (log10 of the ends) and its size in pixels.
struct Frame {
    /// The plot area's top edge, px.
    top: f64,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    pw: f64,
    ph: f64,
}

impl Frame {
    fn px(&self, x: f64) -> f64 {
        LEFT + (x.log10() - self.x0) / (self.x1 - self.x0) * self.pw
    }

    fn py(&self, y: f64) -> f64 {
        self.top + self.ph - (y.log10() - self.y0) / (self.y1 - self.y0) * self.ph
    }

    /// Grid lines at 1..9 times each decade (the decades solid and labelled, the rest light),
    /// vertical ones first.
    fn write_grid(&self, s: &mut String) {
        for (d, k, v) in grid_values(self.x0, self.x1) {
            let x = self.px(v);
            let (c, w) = grid_stroke(k);
            let _ = writeln!(
                s,
                r#"<line x1="{x:.2}" y1="{}" x2="{x:.2}" y2="{:.2}" stroke="{c}" stroke-width="{w}"/>"#,
                self.top,
                self.top + self.ph
            );
            if k == 1 {
                let _ = writeln!(
                    s,
                    r#"<text x="{x:.2}" y="{:.2}" text-anchor="middle">1e{d}</text>"#,
                    self.top + self.ph + 18.0
                );
            }
        }
        for (d, k, v) in grid_values(self.y0, self.y1) {
            let y = self.py(v);
            let (c, w) = grid_stroke(k);
            let _ = writeln!(
                s,
                r#"<line x1="{LEFT}" y1="{y:.2}" x2="{:.2}" y2="{y:.2}" stroke="{c}" stroke-width="{w}"/>"#,
                LEFT + self.pw
            );
            if k == 1 {
                let _ = writeln!(
                    s,
                    r#"<text x="{:.2}" y="{:.2}" text-anchor="end">1e{d}</text>"#,
                    LEFT - 8.0,
                    y + 4.0
                );
            }
        }
    }
}

/// (decade, multiple k = 1..9, value k 10^decade) of the grid lines from decade `lo` up to
/// `hi` (log10).
fn grid_values(lo: f64, hi: f64) -> Vec<(i64, u32, f64)> {
    let mut out = Vec::new();
    for d in (lo as i64)..=(hi as i64) {
        for k in 1..10u32 {
            let v = 10f64.powi(d as i32) * k as f64;
            if v.log10() > hi + 1e-9 {
                break;
            }
            out.push((d, k, v));
        }
    }
    out
}

/// Colour and width of a grid line: decades darker.
fn grid_stroke(k: u32) -> (&'static str, f64) {
    if k == 1 {
        ("#bbbbbb", 1.0)
    } else {
        ("#eeeeee", 0.7)
    }
}

fn esc(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_has_series_band_and_legend() {
        let p = LogLogPlot {
            title: "t <1>".into(),
            subtitle: String::new(),
            notes: Vec::new(),
            x_label: "tau (s)".into(),
            y_label: "dev".into(),
            series: vec![Series::new(
                "oadev",
                vec![0.1, 1.0, 10.0],
                vec![1.0, 0.3, 0.1],
                PALETTE[0],
            )],
            bands: vec![Band {
                name: "1-sigma".into(),
                x: vec![0.1, 1.0, 10.0],
                lo: vec![0.9, 0.25, 0.05],
                hi: vec![1.1, 0.35, 0.2],
                color: PALETTE[0].into(),
            }],
        };
        let svg = p.to_svg();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("t &lt;1&gt;") && svg.contains("1-sigma") && svg.contains("oadev"));
        assert_eq!(svg.matches("<circle").count(), 3);
        assert!(svg.contains(r#"fill-opacity="0.2""#));
        // x axis spans 1e-1 .. 1e1: tick labels of the decades
        assert!(svg.contains(">1e-1<") && svg.contains(">1e1<"));
    }

    #[test]
    fn wrap_keeps_every_line_within_the_width() {
        let text = "heading_rad: measured vs model (bias = each channel's mean over the log; attitude perfect at each segment's start)";
        let lines = wrap(text, 16.0, 400.0);
        assert!(lines.len() >= 2, "{lines:?}");
        assert!(
            lines.iter().all(|l| text_width(l, 16.0) <= 400.0),
            "{lines:?}"
        );
        assert_eq!(lines.join(" "), text);
        // A word longer than the width is cut, not left sticking out.
        let long = wrap(&"x".repeat(100), 12.0, 100.0);
        assert!(
            long.iter().all(|l| text_width(l, 12.0) <= 100.0),
            "{long:?}"
        );
    }
}
