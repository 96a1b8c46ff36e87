//! Output of `vcx bench figures`: markdown tables, SVG plots (`plotters`), the machine,
//! the command line and the date.

use core::fmt::Write as _;

use plotters::prelude::*;

use super::{Plot, Series, Table, NAIVE_ENV};

pub(super) fn series(label: &str, points: Vec<(f64, f64)>) -> Series {
    Series {
        label: label.to_string(),
        points,
    }
}

/// `1234567` → `1,234,567`.
pub(super) fn thousands(v: usize) -> String {
    let digits = v.to_string();
    let mut out = String::new();
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

pub(super) fn markdown_table(t: &Table) -> String {
    let mut s = String::from("|");
    for h in &t.header {
        let _ = write!(s, " {} |", h.trim_start_matches('<'));
    }
    s.push_str("\n|");
    for h in &t.header {
        s.push_str(if h.starts_with('<') { "---|" } else { "---:|" });
    }
    s.push('\n');
    for row in &t.rows {
        s.push('|');
        for cell in row {
            let _ = write!(s, " {cell} |");
        }
        s.push('\n');
    }
    s
}

/// The range of the finite values (positive ones on a log axis), widened a little.
fn axis(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return if log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / 1.5, hi * 1.5)
    } else {
        let pad = ((hi - lo) * 0.05).max(hi.abs() * 0.05).max(1e-9);
        (
            (lo - pad).min(if lo >= 0.0 { 0.0 } else { lo - pad }),
            hi + pad,
        )
    }
}

/// A tick label: `16`, `2.5`, `0.004`, `2e6`.
fn short(v: f64) -> String {
    let a = v.abs();
    if a >= 1e6 {
        format!("{v:.0e}")
    } else if a >= 100.0 || v == v.round() {
        format!("{v:.0}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// The legend goes where the first curve is not: upper left if it rises, else upper right.
fn legend_position(plot: &Plot) -> SeriesLabelPosition {
    let first = plot
        .series
        .first()
        .map(|s| s.points.as_slice())
        .unwrap_or(&[]);
    match (first.first(), first.last()) {
        (Some(a), Some(b)) if b.1 < a.1 => SeriesLabelPosition::UpperRight,
        _ => SeriesLabelPosition::UpperLeft,
    }
}

pub(super) fn render_svg(plot: &Plot) -> Result<String, String> {
    let xs = axis(
        plot.series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0)),
        plot.log_x,
    );
    let ys = axis(
        plot.series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1)),
        plot.log_y,
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 460)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (x, y) = (xs.0..xs.1, ys.0..ys.1);
        match (plot.log_x, plot.log_y) {
            (true, true) => draw(&root, plot, x.log_scale(), y.log_scale()),
            (true, false) => draw(&root, plot, x.log_scale(), y),
            (false, true) => draw(&root, plot, x, y.log_scale()),
            (false, false) => draw(&root, plot, x, y),
        }?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

fn draw<X, Y>(
    root: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    plot: &Plot,
    x: X,
    y: Y,
) -> Result<(), String>
where
    X: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    Y: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    X::CoordDescType: plotters::coord::ranged1d::ValueFormatter<f64>,
    Y::CoordDescType: plotters::coord::ranged1d::ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<_>| e.to_string();
    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x, y)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(plot.x_label)
        .y_desc(plot.y_label)
        .x_label_formatter(&|v| short(*v))
        .y_label_formatter(&|v| short(*v))
        .draw()
        .map_err(e)?;
    for (i, s) in plot.series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|&(x, y)| {
                x.is_finite()
                    && y.is_finite()
                    && (!plot.log_x || x > 0.0)
                    && (!plot.log_y || y > 0.0)
            })
            .collect();
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
            .map_err(e)?
            .label(s.label.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(PointSeries::of_element(
                pts.iter().copied(),
                4,
                color.filled(),
                &|c, s, st| Circle::new(c, s, st),
            ))
            .map_err(e)?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(legend_position(plot))
        .draw()
        .map_err(e)?;
    Ok(())
}

pub(super) fn read_trimmed(path: &str) -> Option<String> {
    std::fs::read_to_string(path)
        .ok()
        .map(|s| s.trim().to_string())
}

/// The machine and the toolchain.
pub(super) struct Machine {
    pub cpu: String,
    pub cores: usize,
    pub memory: String,
    pub rustc: String,
    pub profile: &'static str,
}

/// CPU model, logical cores, memory and the compiler, from /proc and `rustc --version`.
pub(super) fn machine() -> Machine {
    let cpu = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = cpu
        .lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split(':').nth(1))
        .map_or("unknown CPU".to_string(), |m| m.trim().to_string());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mem = std::fs::read_to_string("/proc/meminfo")
        .unwrap_or_default()
        .lines()
        .find(|l| l.starts_with("MemTotal:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|kb| kb.parse::<f64>().ok())
        .map_or("unknown".to_string(), |kb| {
            format!("{:.1} GiB", kb / 1024.0 / 1024.0)
        });
    let rustc = output_of("rustc", &["--version"]).unwrap_or_else(|| "rustc not found".into());
    let profile = if cfg!(debug_assertions) {
        "debug"
    } else {
        "release"
    };
    Machine {
        cpu: model,
        cores,
        memory: mem,
        rustc,
        profile,
    }
}

/// The first line of a command's standard output, if it ran and printed one.
fn output_of(program: &str, args: &[&str]) -> Option<String> {
    let o = std::process::Command::new(program)
        .args(args)
        .output()
        .ok()?;
    let text = String::from_utf8(o.stdout).ok()?;
    let line = text.lines().next()?.trim().to_string();
    (o.status.success() && !line.is_empty()).then_some(line)
}

/// The commit of the working directory, and whether it has uncommitted changes.
pub(super) fn git_revision() -> Option<String> {
    let rev = output_of("git", &["rev-parse", "--short", "HEAD"])?;
    let dirty = output_of("git", &["status", "--porcelain", "--untracked-files=no"]).is_some();
    Some(if dirty {
        format!("`{rev}` with uncommitted changes")
    } else {
        format!("`{rev}`")
    })
}

pub(super) fn command_line() -> String {
    let args: Vec<String> = std::env::args().collect();
    let mut s = String::from("vcx");
    for a in args.iter().skip(1) {
        s.push(' ');
        s.push_str(a);
    }
    if let Some(naive) = std::env::var_os(NAIVE_ENV).filter(|v| !v.is_empty()) {
        s = format!("{NAIVE_ENV}={} {s}", naive.to_string_lossy());
    }
    if std::env::var("VCX_FIGURES_TINY").is_ok_and(|v| v == "1") {
        s = format!("VCX_FIGURES_TINY=1 {s}");
    }
    s
}

/// The current UTC date and time, `YYYY-MM-DD HH:MM UTC` (civil from days, proleptic
/// Gregorian calendar).
pub(super) fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rem / 3600,
        (rem % 3600) / 60
    )
}
