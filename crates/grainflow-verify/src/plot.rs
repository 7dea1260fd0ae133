//! Figures (PNG and SVG) for the verification reports.
//!
//! A [`Figure`] is a row of [`Panel`]s, each an x–y chart with its own axes, title, light grid
//! and legend. [`write_figure`] renders it twice, to a PNG and to an SVG, each written atomically
//! (rendered beside the target under a temporary name, then renamed). Text uses the DejaVu Sans
//! font embedded in the crate, so no system fonts or libraries are needed.
//!
//! ```no_run
//! use grainflow_verify::plot::*;
//! let fig = Figure {
//!     title: "Free fall".into(),
//!     note: Some("reference: analytical solution".into()),
//!     panels: vec![Panel {
//!         series: vec![
//!             Series::line("theory", vec![(0.0, 0.0), (1.0, 4.9)], LineStyle::Thin, Color::BLACK),
//!             Series::markers("grainflow", vec![(0.5, 1.2), (1.0, 4.9)], MarkerShape::Circle, Color::BLUE),
//!         ],
//!         ..Panel::new("drop height", "time [s]", "height [m]")
//!     }],
//! };
//! write_figure(&fig, "fall.png".as_ref(), "fall.svg".as_ref()).unwrap();
//! ```

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

use plotters::coord::Shift;
use plotters::coord::ranged1d::{BoldPoints, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::element::{DashedPathElement, IntoDynElement};
use plotters::prelude::{
    BitMapBackend, BitMapElement, ChartBuilder, Circle, Cross, DrawingArea, DrawingBackend, EmptyElement,
    IntoDrawingArea, IntoFont, MultiLineText, PathElement, RGBColor, Rectangle, SVGBackend,
    SeriesLabelPosition, ShapeStyle, TextStyle, TriangleMarker,
};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{Color as _, FontStyle};

/// Pixel size of one panel (width, height); the figure is `panels × PANEL_W` wide.
const PANEL_W: u32 = 600;
const PANEL_H: u32 = 600;

/// Font sizes (plotters units, i.e. the glyph box height in pixels).
const TITLE_SIZE: f64 = 26.0;
const NOTE_SIZE: f64 = 15.0;
const PANEL_TITLE_SIZE: f64 = 21.0;
const AXIS_DESC_SIZE: f64 = 18.0;
const TICK_SIZE: f64 = 15.0;
const LEGEND_SIZE: f64 = 15.0;

/// Stroke widths and dash pattern (pixels).
const LINE_WIDTH: f64 = 2.0;
const THIN_WIDTH: f64 = 1.0;
const DASH_ON: f64 = 10.0;
const DASH_OFF: f64 = 7.0;
const MARKER_SIZE: f64 = 5.0;

/// Legend geometry (pixels), as laid out by plotters' `SeriesLabelStyle`.
const LEGEND_SYMBOL_AREA: f64 = 42.0;
const LEGEND_SYMBOL_LEN: f64 = 32.0;
const LEGEND_MARGIN: f64 = 8.0;
/// Gap between the legend box and the plot frame.
const LEGEND_EDGE: f64 = 6.0;
/// Tick mark length; plotters puts tick labels at twice this distance from the axis.
const TICK_MARK: f64 = 5.0;

/// The PNG is rendered at this multiple of its size and averaged down (anti-aliasing).
const SUPERSAMPLE: u32 = 2;

const FONT_FAMILY: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// How a [`SeriesStyle::Line`] is stroked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineStyle {
    /// Solid line, 2 px.
    Solid,
    /// Dashed line, 2 px.
    Dashed,
    /// Thin solid line, 1 px (e.g. for a theoretical curve).
    Thin,
}

/// Marker drawn at each point of a [`SeriesStyle::Markers`] series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MarkerShape {
    Circle,
    Triangle,
    Square,
    Cross,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeriesStyle {
    /// Points joined in order; the line breaks at non-finite points.
    Line { style: LineStyle, color: Color },
    /// One marker per finite point.
    Markers { shape: MarkerShape, color: Color },
}

/// An RGB colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Color(pub u8, pub u8, pub u8);

impl Color {
    pub const BLACK: Color = Color(0, 0, 0);
    pub const BLUE: Color = Color(31, 119, 180);
    pub const ORANGE: Color = Color(255, 127, 14);
    pub const GREEN: Color = Color(44, 160, 44);
    pub const RED: Color = Color(214, 39, 40);
    pub const PURPLE: Color = Color(148, 103, 189);
    pub const BROWN: Color = Color(140, 86, 75);
    pub const GREY: Color = Color(127, 127, 127);

    /// A qualitative palette for series without a natural colour: cycles through
    /// blue, orange, green, red, purple, brown, grey.
    pub fn palette(i: usize) -> Color {
        const P: [Color; 7] =
            [Color::BLUE, Color::ORANGE, Color::GREEN, Color::RED, Color::PURPLE, Color::BROWN, Color::GREY];
        P[i % P.len()]
    }

    fn rgb(self) -> RGBColor {
        RGBColor(self.0, self.1, self.2)
    }
}

/// One data series of a panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text; an empty label leaves the series out of the legend.
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub style: SeriesStyle,
}

impl Series {
    /// A line series.
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>, style: LineStyle, color: Color) -> Self {
        Series { label: label.into(), points, style: SeriesStyle::Line { style, color } }
    }

    /// A marker (scatter) series.
    pub fn markers(
        label: impl Into<String>,
        points: Vec<(f64, f64)>,
        shape: MarkerShape,
        color: Color,
    ) -> Self {
        Series { label: label.into(), points, style: SeriesStyle::Markers { shape, color } }
    }
}

/// One chart of a figure.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Fixed x range; `None` spans all finite points with 5 % padding.
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range; `None` spans all finite points with 5 % padding (plus headroom for the
    /// legend when it would otherwise cover data).
    pub y_range: Option<(f64, f64)>,
    pub series: Vec<Series>,
}

impl Panel {
    /// An empty panel with automatic ranges.
    pub fn new(title: impl Into<String>, x_label: impl Into<String>, y_label: impl Into<String>) -> Self {
        Panel { title: title.into(), x_label: x_label.into(), y_label: y_label.into(), ..Panel::default() }
    }
}

/// A row of panels under a common title.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Figure {
    pub title: String,
    pub panels: Vec<Panel>,
    /// A line of small text under the title, e.g. the data source.
    pub note: Option<String>,
}

impl Figure {
    /// Pixel size (width, height) of the rendered figure.
    pub fn size(&self) -> (u32, u32) {
        (PANEL_W * self.panels.len().max(1) as u32, PANEL_H)
    }
}

/// Failure to write a figure.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("cannot write figure {}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot draw figure {}: {message}", path.display())]
    Draw { path: PathBuf, message: String },
    #[error("cannot load the embedded font: {0}")]
    Font(String),
}

/// Renders `fig` to a PNG and an SVG file. Each file is first written beside its target under
/// a temporary name and then renamed, so a reader never sees a partial file.
pub fn write_figure(fig: &Figure, png: &Path, svg: &Path) -> Result<(), PlotError> {
    ensure_font()?;
    let size = fig.size();

    // PNG: drawn at SUPERSAMPLE × the size into memory, averaged down, then handed to plotters'
    // bitmap backend, which encodes through the `image` crate; that crate chooses the format
    // from the extension, so the temporary file keeps a `.png` suffix.
    let ss = SUPERSAMPLE;
    let mut big = vec![255u8; (size.0 * ss * size.1 * ss * 3) as usize];
    let drawn = {
        let root = BitMapBackend::with_buffer(&mut big, (size.0 * ss, size.1 * ss)).into_drawing_area();
        draw_figure(&root, fig, Metrics { s: ss as f64 }).and_then(|()| root.present().map_err(err))
    };
    if let Err(message) = drawn {
        return Err(PlotError::Draw { path: png.to_path_buf(), message });
    }
    let small = downsample(&big, size, ss);
    drop(big);
    let tmp = temp_path(png, Some("png"));
    let io_err = |source| PlotError::Io { path: png.to_path_buf(), source };
    // Create the file first so that a missing folder or a permission problem is an I/O error.
    fs::File::create(&tmp).map_err(io_err)?;
    let drawn = {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        BitMapElement::with_owned_buffer((0, 0), size, small)
            .ok_or_else(|| "bitmap buffer has the wrong size".to_string())
            .and_then(|image| root.draw(&image).map_err(err))
            .and_then(|()| root.present().map_err(err))
    };
    if let Err(message) = drawn {
        let _ = fs::remove_file(&tmp);
        return Err(PlotError::Draw { path: png.to_path_buf(), message });
    }
    if let Err(e) = fs::rename(&tmp, png) {
        let _ = fs::remove_file(&tmp);
        return Err(io_err(e));
    }

    // SVG: render to a string, then write and rename.
    let mut text = String::new();
    let drawn = {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw_figure(&root, fig, Metrics { s: 1.0 }).and_then(|()| root.present().map_err(err))
    };
    if let Err(message) = drawn {
        return Err(PlotError::Draw { path: svg.to_path_buf(), message });
    }
    let tmp = temp_path(svg, None);
    let io_err = |source| PlotError::Io { path: svg.to_path_buf(), source };
    if let Err(e) = fs::write(&tmp, text.as_bytes()).and_then(|()| fs::rename(&tmp, svg)) {
        let _ = fs::remove_file(&tmp);
        return Err(io_err(e));
    }
    Ok(())
}

/// Registers the embedded font under the family name used by every text style here.
fn ensure_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, FONT_BYTES)
                .map_err(|_| "DejaVuSans.ttf is not a valid font".to_string())
        })
        .clone()
        .map_err(PlotError::Font)
}

/// `dir/name.partial-<pid>-<n>[.ext]` beside `target`.
fn temp_path(target: &Path, ext: Option<&str>) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut name = target.file_name().map(|s| s.to_os_string()).unwrap_or_else(|| "figure".into());
    name.push(format!(".partial-{}-{n}", std::process::id()));
    if let Some(ext) = ext {
        name.push(".");
        name.push(ext);
    }
    target.with_file_name(name)
}

/// Averages `ss × ss` pixel blocks of an RGB image of `size × ss` down to `size`.
fn downsample(big: &[u8], (w, h): (u32, u32), ss: u32) -> Vec<u8> {
    let (w, h, ss) = (w as usize, h as usize, ss as usize);
    let big_w = w * ss;
    let mut out = vec![0u8; w * h * 3];
    let n = (ss * ss) as u32;
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0u32; 3];
            for dy in 0..ss {
                let row = (y * ss + dy) * big_w;
                for dx in 0..ss {
                    let i = (row + x * ss + dx) * 3;
                    for c in 0..3 {
                        acc[c] += u32::from(big[i + c]);
                    }
                }
            }
            let o = (y * w + x) * 3;
            for c in 0..3 {
                out[o + c] = ((acc[c] + n / 2) / n) as u8;
            }
        }
    }
    out
}

/// Pixel scale of one rendering: sizes below are given for the output image and multiplied
/// by `s` when drawing (the PNG is drawn supersampled).
#[derive(Clone, Copy, Debug)]
struct Metrics {
    s: f64,
}

impl Metrics {
    fn px(self, v: f64) -> i32 {
        (v * self.s).round() as i32
    }

    fn upx(self, v: f64) -> u32 {
        self.px(v).max(0) as u32
    }

    fn font(self, size: f64) -> TextStyle<'static> {
        font(size * self.s)
    }

    fn text_width(self, text: &str, size: f64) -> i32 {
        text_width(text, size * self.s)
    }
}

fn font(size: f64) -> TextStyle<'static> {
    (FONT_FAMILY, size).into_font().into()
}

fn text_width(text: &str, size: f64) -> i32 {
    (FONT_FAMILY, size)
        .into_font()
        .box_size(text)
        .map(|(w, _)| w as i32)
        .unwrap_or((text.chars().count() as f64 * size * 0.6) as i32)
}

// ---------------------------------------------------------------------------------------------
// Drawing
// ---------------------------------------------------------------------------------------------

fn draw_figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    m: Metrics,
) -> Result<(), String> {
    root.fill(&plotters::style::WHITE).map_err(err)?;
    let (w, _) = root.dim_in_pixel();

    // Header: title and optional note, centred.
    let mut header_h = m.px(12.0);
    if !fig.title.is_empty() {
        let style = m.font(TITLE_SIZE).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw_text(&fig.title, &style, (w as i32 / 2, header_h)).map_err(err)?;
        header_h += m.px(TITLE_SIZE + 6.0);
    }
    if let Some(note) = fig.note.as_deref().filter(|n| !n.is_empty()) {
        let style = m.font(NOTE_SIZE).color(&RGBColor(90, 90, 90)).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw_text(note, &style, (w as i32 / 2, header_h)).map_err(err)?;
        header_h += m.px(NOTE_SIZE + 6.0);
    }
    header_h += m.px(4.0);

    if fig.panels.is_empty() {
        return Ok(());
    }
    let (_, body) = root.split_vertically(header_h);
    let areas = body.split_evenly((1, fig.panels.len()));
    for (area, panel) in areas.iter().zip(&fig.panels) {
        draw_panel(area, panel, m)?;
    }
    Ok(())
}

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// A fixed choice of tick-label format for one axis.
#[derive(Clone, Copy, Debug, PartialEq)]
struct TickFormat {
    decimals: usize,
    scientific: bool,
}

impl TickFormat {
    /// The shortest format that shows every tick of `lo..hi` (with `n` labels) exactly.
    fn for_range(lo: f64, hi: f64, n: usize) -> Self {
        let ticks = tick_values(lo, hi, n);
        let max_abs = ticks.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let step = ticks.windows(2).map(|w| (w[1] - w[0]).abs()).fold(f64::INFINITY, f64::min);
        let step = if step.is_finite() && step > 0.0 { step } else { (hi - lo).abs().max(f64::MIN_POSITIVE) };
        let scientific = max_abs >= 1e5 || (max_abs > 0.0 && max_abs < 1e-3);
        for decimals in 0..=12 {
            let f = TickFormat { decimals, scientific };
            let exact =
                ticks.iter().all(|&v| f.format(v).parse::<f64>().is_ok_and(|p| (p - v).abs() <= step * 1e-3));
            if exact {
                return f;
            }
        }
        TickFormat { decimals: 12, scientific }
    }

    fn format(&self, v: f64) -> String {
        // Avoid "-0.0".
        let v = if v == 0.0 { 0.0 } else { v };
        if self.scientific {
            if v == 0.0 { "0".to_string() } else { format!("{:.*e}", self.decimals, v) }
        } else {
            let s = format!("{:.*}", self.decimals, v);
            if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
                s[1..].to_string()
            } else {
                s
            }
        }
    }
}

fn tick_values(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    RangedCoordf64::from(lo..hi).key_points(BoldPoints(n))
}

/// Number of x tick labels that fit side by side in `width` pixels.
fn x_label_count(lo: f64, hi: f64, width: i32, m: Metrics) -> usize {
    for n in (3..=8).rev() {
        let f = TickFormat::for_range(lo, hi, n);
        let ticks = tick_values(lo, hi, n);
        let widest = ticks.iter().map(|&v| m.text_width(&f.format(v), TICK_SIZE)).max().unwrap_or(0);
        if (ticks.len() as i32) * (widest + m.px(24.0)) <= width {
            return n;
        }
    }
    3
}

const Y_LABELS: usize = 8;

/// Width of the y label area: widest tick label, tick, gaps and the rotated axis label.
fn y_label_area(lo: f64, hi: f64, has_desc: bool, m: Metrics) -> u32 {
    let f = TickFormat::for_range(lo, hi, Y_LABELS);
    let widest = tick_values(lo, hi, Y_LABELS)
        .iter()
        .map(|&v| m.text_width(&f.format(v), TICK_SIZE))
        .max()
        .unwrap_or(0);
    // Tick labels end `2 × tick size` = 10 px left of the axis; the rotated description sits
    // at the left edge of the area.
    let desc = if has_desc { AXIS_DESC_SIZE + 8.0 } else { 0.0 };
    (widest + m.px(2.0 * TICK_MARK + 4.0 + desc)).max(m.px(30.0)) as u32
}

fn x_label_area(has_desc: bool, m: Metrics) -> u32 {
    let ticks = 2.0 * TICK_MARK + TICK_SIZE + 2.0;
    let desc = if has_desc { AXIS_DESC_SIZE + 6.0 } else { 0.0 };
    m.upx(ticks + desc)
}

/// Automatic range over the finite values, padded by 5 % of the span on both sides.
fn auto_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    if span == 0.0 {
        let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
        return (lo - d, hi + d);
    }
    if !span.is_finite() {
        return (lo, hi);
    }
    (lo - 0.05 * span, hi + 0.05 * span)
}

/// A user range made usable: ordered, finite, non-degenerate; `None` if unusable.
fn fixed_range(r: Option<(f64, f64)>) -> Option<(f64, f64)> {
    let (a, b) = r?;
    if !(a.is_finite() && b.is_finite()) {
        return None;
    }
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    if lo == hi {
        let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
        return Some((lo - d, hi + d));
    }
    Some((lo, hi))
}

/// Clips segment `p`–`q` to the box (Liang–Barsky). Returns the clipped ends and whether each
/// end was moved.
#[allow(clippy::type_complexity)]
fn clip_segment(
    p: (f64, f64),
    q: (f64, f64),
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Option<((f64, f64), (f64, f64), bool, bool)> {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let mut t0 = 0.0f64;
    let mut t1 = 1.0f64;
    for (pk, qk) in [(-dx, p.0 - x0), (dx, x1 - p.0), (-dy, p.1 - y0), (dy, y1 - p.1)] {
        if pk == 0.0 {
            if qk < 0.0 {
                return None;
            }
        } else {
            let r = qk / pk;
            if pk < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    if t0 > t1 || !t0.is_finite() || !t1.is_finite() {
        return None;
    }
    let a = if t0 > 0.0 { (p.0 + t0 * dx, p.1 + t0 * dy) } else { p };
    let b = if t1 < 1.0 { (p.0 + t1 * dx, p.1 + t1 * dy) } else { q };
    Some((a, b, t0 > 0.0, t1 < 1.0))
}

/// Splits a polyline into runs that are finite and inside the box; a line breaks at
/// non-finite points and where it leaves the box.
fn line_runs(points: &[(f64, f64)], xr: (f64, f64), yr: (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let mut runs = Vec::new();
    let mut run: Vec<(f64, f64)> = Vec::new();
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    for w in points.windows(2) {
        let (p, q) = (w[0], w[1]);
        let clipped = if finite(&p) && finite(&q) { clip_segment(p, q, xr, yr) } else { None };
        match clipped {
            Some((a, b, a_moved, b_moved)) => {
                if run.is_empty() || a_moved {
                    if run.len() > 1 {
                        runs.push(std::mem::take(&mut run));
                    }
                    run.clear();
                    run.push(a);
                }
                run.push(b);
                if b_moved {
                    runs.push(std::mem::take(&mut run));
                }
            }
            None => {
                if run.len() > 1 {
                    runs.push(std::mem::take(&mut run));
                }
                run.clear();
            }
        }
    }
    if run.len() > 1 {
        runs.push(run);
    }
    runs
}

fn marker_points(points: &[(f64, f64)], xr: (f64, f64), yr: (f64, f64)) -> Vec<(f64, f64)> {
    let (ex, ey) = ((xr.1 - xr.0) * 1e-9, (yr.1 - yr.0) * 1e-9);
    points
        .iter()
        .copied()
        .filter(|&(x, y)| {
            x.is_finite()
                && y.is_finite()
                && x >= xr.0 - ex
                && x <= xr.1 + ex
                && y >= yr.0 - ey
                && y <= yr.1 + ey
        })
        .collect()
}

fn line_shape(style: LineStyle, color: Color, m: Metrics) -> ShapeStyle {
    let width = match style {
        LineStyle::Thin => THIN_WIDTH,
        LineStyle::Solid | LineStyle::Dashed => LINE_WIDTH,
    };
    color.rgb().stroke_width(m.upx(width).max(1))
}

/// Candidate legend positions, in order of preference.
const LEGEND_POSITIONS: [SeriesLabelPosition; 8] = [
    SeriesLabelPosition::UpperRight,
    SeriesLabelPosition::UpperLeft,
    SeriesLabelPosition::LowerRight,
    SeriesLabelPosition::LowerLeft,
    SeriesLabelPosition::UpperMiddle,
    SeriesLabelPosition::LowerMiddle,
    SeriesLabelPosition::MiddleRight,
    SeriesLabelPosition::MiddleLeft,
];

/// Legend box `[x0, y0, x1, y1]` inside a plot of size `dim` (plot pixel coordinates).
fn legend_box(pos: &SeriesLabelPosition, size: (i32, i32), dim: (u32, u32), m: Metrics) -> [i32; 4] {
    use SeriesLabelPosition::*;
    let (w, h) = size;
    let (aw, ah) = (dim.0 as i32, dim.1 as i32);
    let edge = m.px(LEGEND_EDGE);
    let x = match pos {
        UpperLeft | MiddleLeft | LowerLeft => edge,
        UpperMiddle | MiddleMiddle | LowerMiddle => (aw - w) / 2,
        UpperRight | MiddleRight | LowerRight => aw - w - edge,
        Coordinate(x, _) => *x,
    };
    let y = match pos {
        UpperLeft | UpperMiddle | UpperRight => edge,
        MiddleLeft | MiddleMiddle | MiddleRight => (ah - h) / 2,
        LowerLeft | LowerMiddle | LowerRight => ah - h - edge,
        Coordinate(_, y) => *y,
    };
    [x, y, x + w, y + h]
}

/// Series geometry clipped to the final ranges.
enum Prepared<'a> {
    Line { series: &'a Series, style: LineStyle, color: Color, runs: Vec<Vec<(f64, f64)>> },
    Markers { series: &'a Series, shape: MarkerShape, color: Color, points: Vec<(f64, f64)> },
}

fn prepare(panel: &Panel, xr: (f64, f64), yr: (f64, f64)) -> Vec<Prepared<'_>> {
    panel
        .series
        .iter()
        .map(|s| match s.style {
            SeriesStyle::Line { style, color } => {
                Prepared::Line { series: s, style, color, runs: line_runs(&s.points, xr, yr) }
            }
            SeriesStyle::Markers { shape, color } => {
                Prepared::Markers { series: s, shape, color, points: marker_points(&s.points, xr, yr) }
            }
        })
        .collect()
}

/// Pixel positions (inside the plot) that the drawn data occupies, for legend placement.
fn data_samples(
    prepared: &[Prepared<'_>],
    xr: (f64, f64),
    yr: (f64, f64),
    dim: (u32, u32),
) -> Vec<(f64, f64)> {
    let (w, h) = (dim.0 as f64, dim.1 as f64);
    let to_px = |(x, y): (f64, f64)| ((x - xr.0) / (xr.1 - xr.0) * w, (1.0 - (y - yr.0) / (yr.1 - yr.0)) * h);
    let mut out = Vec::new();
    for p in prepared {
        match p {
            Prepared::Line { runs, .. } => {
                for run in runs {
                    for seg in run.windows(2) {
                        let (a, b) = (to_px(seg[0]), to_px(seg[1]));
                        let len = (b.0 - a.0).hypot(b.1 - a.1);
                        let n = ((len / 3.0).ceil() as usize).clamp(1, 100_000);
                        for i in 0..=n {
                            let t = i as f64 / n as f64;
                            out.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
                        }
                    }
                }
            }
            Prepared::Markers { points, .. } => out.extend(points.iter().map(|&q| to_px(q))),
        }
    }
    out
}

/// Number of samples hidden by a legend box (enlarged by a few pixels).
fn legend_cost(bx: [i32; 4], samples: &[(f64, f64)], m: Metrics) -> usize {
    let pad = m.s * (MARKER_SIZE + 3.0);
    let [x0, y0, x1, y1] = bx.map(f64::from);
    samples
        .iter()
        .filter(|(x, y)| *x >= x0 - pad && *x <= x1 + pad && *y >= y0 - pad && *y <= y1 + pad)
        .count()
}

/// Legend text size `(w, h)` and the full box size including symbol area and margins.
fn legend_size(labels: &[&str], m: Metrics) -> Result<(i32, i32), String> {
    let style = m.font(LEGEND_SIZE);
    let mut text = MultiLineText::<_, &str>::new((0, 0), &style);
    for l in labels {
        text.push_line(*l);
    }
    let (w, h) = text.estimate_dimension().map_err(err)?;
    Ok((w + m.px(LEGEND_SYMBOL_AREA + 2.0 * LEGEND_MARGIN), h + m.px(2.0 * LEGEND_MARGIN)))
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    m: Metrics,
) -> Result<(), String> {
    let area = area.margin(m.px(4.0), m.px(6.0), m.px(10.0), m.px(18.0));
    let inner = if panel.title.is_empty() {
        area
    } else {
        area.titled(&panel.title, m.font(PANEL_TITLE_SIZE)).map_err(err)?
    };

    // Ranges.
    let all = || panel.series.iter().flat_map(|s| s.points.iter().copied());
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let x_fixed = fixed_range(panel.x_range);
    let y_fixed = fixed_range(panel.y_range);
    let xr = x_fixed.unwrap_or_else(|| {
        // With a fixed y range, only points inside it matter for x (and vice versa).
        let ys = y_fixed.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
        auto_range(all().filter(finite).filter(|p| p.1 >= ys.0 && p.1 <= ys.1).map(|p| p.0))
    });
    let mut yr = y_fixed.unwrap_or_else(|| {
        auto_range(all().filter(finite).filter(|p| p.0 >= xr.0 && p.0 <= xr.1).map(|p| p.1))
    });

    let x_area = x_label_area(!panel.x_label.is_empty(), m);
    let plot_dim = |yr: (f64, f64)| -> Result<(u32, u32), String> {
        let y_area = y_label_area(yr.0, yr.1, !panel.y_label.is_empty(), m);
        let chart = ChartBuilder::on(&inner)
            .margin_top(m.px(8.0))
            .margin_right(m.px(4.0))
            .x_label_area_size(x_area)
            .y_label_area_size(y_area)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(err)?;
        Ok(chart.plotting_area().dim_in_pixel())
    };

    // Legend placement: the preferred corner hiding the least data; with an automatic y range,
    // make headroom above the data when every position would hide some.
    let labels: Vec<&str> = panel.series.iter().map(|s| s.label.as_str()).filter(|l| !l.is_empty()).collect();
    let mut legend_pos = SeriesLabelPosition::UpperRight;
    if !labels.is_empty() {
        let lsize = legend_size(&labels, m)?;
        let best = |yr: (f64, f64)| -> Result<(SeriesLabelPosition, usize, (u32, u32)), String> {
            let dim = plot_dim(yr)?;
            let samples = data_samples(&prepare(panel, xr, yr), xr, yr, dim);
            let mut best = (SeriesLabelPosition::UpperRight, usize::MAX);
            for pos in LEGEND_POSITIONS {
                let cost = legend_cost(legend_box(&pos, lsize, dim, m), &samples, m);
                if cost < best.1 {
                    best = (pos, cost);
                }
            }
            Ok((best.0, best.1, dim))
        };
        let (pos, cost, dim) = best(yr)?;
        legend_pos = pos;
        if cost > 0 && y_fixed.is_none() {
            // Top of the data (auto range is padded by 5 % of the data span).
            let span = (yr.1 - yr.0) / 1.1;
            let (lo, top) = (yr.0, yr.1 - 0.05 * span);
            let f = (lsize.1 + m.px(LEGEND_EDGE + 8.0)) as f64 / dim.1.max(1) as f64;
            if f < 0.5 && span.is_finite() && span > 0.0 {
                let new_hi = (top - f * lo) / (1.0 - f);
                let candidate = (yr.0, new_hi.max(yr.1));
                let (pos, cost2, _) = best(candidate)?;
                if cost2 < cost {
                    yr = candidate;
                    legend_pos = pos;
                }
            }
        }
    }

    // The chart itself.
    let y_area = y_label_area(yr.0, yr.1, !panel.y_label.is_empty(), m);
    let mut chart = ChartBuilder::on(&inner)
        .margin_top(m.px(8.0))
        .margin_right(m.px(4.0))
        .x_label_area_size(x_area)
        .y_label_area_size(y_area)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
        .map_err(err)?;
    let dim = chart.plotting_area().dim_in_pixel();
    let nx = x_label_count(xr.0, xr.1, dim.0 as i32, m);
    let xf = TickFormat::for_range(xr.0, xr.1, nx);
    let yf = TickFormat::for_range(yr.0, yr.1, Y_LABELS);
    // Typographic minus sign in tick labels.
    let x_fmt = |v: &f64| xf.format(*v).replace('-', "\u{2212}");
    let y_fmt = |v: &f64| yf.format(*v).replace('-', "\u{2212}");
    chart
        .configure_mesh()
        .x_labels(nx)
        .y_labels(Y_LABELS)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .label_style(m.font(TICK_SIZE))
        .axis_desc_style(m.font(AXIS_DESC_SIZE))
        .set_all_tick_mark_size(m.px(TICK_MARK))
        .bold_line_style(RGBColor(0, 0, 0).mix(0.12).stroke_width(m.upx(1.0)))
        .light_line_style(plotters::style::TRANSPARENT)
        .axis_style(RGBColor(0, 0, 0).stroke_width(m.upx(1.0)))
        .draw()
        .map_err(err)?;

    // Series, in order (later series on top).
    for p in prepare(panel, xr, yr) {
        match p {
            Prepared::Line { series, style, color, runs } => {
                let shape = line_shape(style, color, m);
                let (on, off) = (m.px(DASH_ON), m.px(DASH_OFF));
                let (legend_on, legend_off) = (m.px(8.0), m.px(5.0));
                let legend_len = m.px(LEGEND_SYMBOL_LEN);
                let anno = match style {
                    LineStyle::Dashed => chart
                        .draw_series(runs.into_iter().map(|run| DashedPathElement::new(run, on, off, shape))),
                    LineStyle::Solid | LineStyle::Thin => {
                        chart.draw_series(runs.into_iter().map(|run| PathElement::new(run, shape)))
                    }
                }
                .map_err(err)?;
                if !series.label.is_empty() {
                    anno.label(series.label.as_str()).legend(move |(x, y)| {
                        let pts = vec![(x, y), (x + legend_len, y)];
                        match style {
                            LineStyle::Dashed => {
                                DashedPathElement::new(pts, legend_on, legend_off, shape).into_dyn()
                            }
                            _ => PathElement::new(pts, shape).into_dyn(),
                        }
                    });
                }
            }
            Prepared::Markers { series, shape, color, points } => {
                let fill = color.rgb().filled();
                let stroke = color.rgb().stroke_width(m.upx(2.0));
                let r = m.px(MARKER_SIZE);
                let one = m.px(1.0);
                let legend_len = m.px(LEGEND_SYMBOL_LEN);
                let pts = points.into_iter();
                let anno = match shape {
                    MarkerShape::Circle => {
                        chart.draw_series(pts.map(|q| EmptyElement::at(q) + Circle::new((0, 0), r, fill)))
                    }
                    MarkerShape::Triangle => chart.draw_series(
                        pts.map(|q| EmptyElement::at(q) + TriangleMarker::new((0, 0), r + one, fill)),
                    ),
                    MarkerShape::Square => chart.draw_series(pts.map(|q| {
                        EmptyElement::at(q) + Rectangle::new([(one - r, one - r), (r - one, r - one)], fill)
                    })),
                    MarkerShape::Cross => {
                        chart.draw_series(pts.map(|q| EmptyElement::at(q) + Cross::new((0, 0), r, stroke)))
                    }
                }
                .map_err(err)?;
                if !series.label.is_empty() {
                    anno.label(series.label.as_str()).legend(move |(x, y)| {
                        // Pixel coordinates here, so plain (DB-independent) elements do.
                        let (cx, cy) = (x + legend_len / 2, y);
                        match shape {
                            MarkerShape::Circle => Circle::new((cx, cy), r, fill).into_dyn(),
                            MarkerShape::Triangle => TriangleMarker::new((cx, cy), r + one, fill).into_dyn(),
                            MarkerShape::Square => Rectangle::new(
                                [(cx + one - r, cy + one - r), (cx + r - one, cy + r - one)],
                                fill,
                            )
                            .into_dyn(),
                            MarkerShape::Cross => Cross::new((cx, cy), r, stroke).into_dyn(),
                        }
                    });
                }
            }
        }
    }

    // Frame around the plot.
    let frame = chart.plotting_area().strip_coord_spec();
    frame
        .draw(&Rectangle::new(
            [(0, 0), (dim.0 as i32 - 1, dim.1 as i32 - 1)],
            RGBColor(0, 0, 0).stroke_width(m.upx(1.0)),
        ))
        .map_err(err)?;

    if !labels.is_empty() {
        let [x, y, _, _] = legend_box(&legend_pos, legend_size(&labels, m)?, dim, m);
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::Coordinate(x, y))
            .legend_area_size(m.upx(LEGEND_SYMBOL_AREA))
            .margin(m.upx(LEGEND_MARGIN))
            .label_font(m.font(LEGEND_SIZE))
            .background_style(plotters::style::WHITE.mix(0.9))
            .border_style(RGBColor(0, 0, 0).mix(0.35))
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn demo_figure() -> Figure {
        let theory: Vec<(f64, f64)> = (0..=200)
            .map(|i| {
                let t = i as f64 * 0.01;
                (t, (-t).exp() * (8.0 * t).cos())
            })
            .collect();
        let dashed: Vec<(f64, f64)> = theory.iter().map(|&(t, y)| (t, 0.8 * y)).collect();
        let mut solid: Vec<(f64, f64)> = theory.iter().map(|&(t, y)| (t, y + 0.05)).collect();
        solid[50].1 = f64::NAN;
        solid[120] = (f64::INFINITY, 0.0);
        let sim: Vec<(f64, f64)> = theory.iter().step_by(10).copied().collect();
        let mut panel = Panel::new("Velocity", "time t [s]", "v [m/s]");
        panel.series = vec![
            Series::line("theory", theory, LineStyle::Thin, Color::BLACK),
            Series::line("damped 0.8", dashed, LineStyle::Dashed, Color::RED),
            Series::line("solid + NaN", solid, LineStyle::Solid, Color::BLUE),
            Series::markers("grainflow", sim, MarkerShape::Circle, Color::ORANGE),
        ];
        let mut second = Panel::new("Markers", "x", "y");
        second.series = vec![
            Series::markers(
                "triangles",
                (0..10).map(|i| (i as f64, i as f64 * 2.0)).collect(),
                MarkerShape::Triangle,
                Color::GREEN,
            ),
            Series::markers(
                "squares",
                (0..10).map(|i| (i as f64, 20.0 - i as f64)).collect(),
                MarkerShape::Square,
                Color::GREY,
            ),
            Series::markers(
                "crosses",
                vec![(1.0, 5.0), (f64::NAN, 1.0), (5.0, f64::NEG_INFINITY)],
                MarkerShape::Cross,
                Color::BLUE,
            ),
            Series::line("empty", vec![], LineStyle::Solid, Color::RED),
        ];
        let mut third = Panel::new("Fixed ranges", "x", "y");
        third.x_range = Some((0.0, 1.0));
        third.y_range = Some((-0.5, 0.5));
        third.series = vec![Series::line(
            "clipped dashes",
            (0..=100).map(|i| (i as f64 * 0.02 - 0.5, (i as f64 * 0.1).sin())).collect(),
            LineStyle::Dashed,
            Color::GREEN,
        )];
        Figure {
            title: "Demo figure".into(),
            panels: vec![panel, second, third],
            note: Some("data: synthetic".into()),
        }
    }

    fn png_size(bytes: &[u8]) -> (u32, u32) {
        assert!(bytes.len() > 24, "PNG too short");
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
        assert_eq!(&bytes[12..16], b"IHDR");
        let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
        let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
        (w, h)
    }

    #[test]
    fn plot_writes_png_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let (png, svg) = (dir.path().join("demo.png"), dir.path().join("demo.svg"));
        let fig = demo_figure();
        write_figure(&fig, &png, &svg).unwrap();

        let bytes = fs::read(&png).unwrap();
        assert_eq!(png_size(&bytes), (1800, 600));
        assert_eq!(fig.size(), (1800, 600));

        let text = fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg"), "{}", &text[..100.min(text.len())]);
        for needle in [
            "Demo figure",
            "data: synthetic",
            "Velocity",
            "time t [s]",
            "theory",
            "damped 0.8",
            "solid + NaN",
            "grainflow",
            "triangles",
            "clipped dashes",
        ] {
            assert!(text.contains(needle), "SVG lacks {needle:?}");
        }
        // The dashed red series is drawn as many separate polylines (one per dash).
        let red = "stroke=\"#D62728\"";
        let dashes = text.lines().filter(|l| l.contains(red)).count();
        assert!(dashes > 20, "only {dashes} red polylines");

        // No temporary files are left behind.
        let names: Vec<_> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
    }

    #[test]
    fn plot_png_size_scales_with_panels() {
        let dir = tempfile::tempdir().unwrap();
        let (png, svg) = (dir.path().join("one.png"), dir.path().join("one.svg"));
        let mut fig = demo_figure();
        fig.panels.truncate(1);
        write_figure(&fig, &png, &svg).unwrap();
        assert_eq!(png_size(&fs::read(&png).unwrap()), (600, 600));
    }

    #[test]
    fn plot_degenerate_input_does_not_panic() {
        let dir = tempfile::tempdir().unwrap();
        let (png, svg) = (dir.path().join("d.png"), dir.path().join("d.svg"));
        let mut all_nan = Panel::new("", "", "");
        all_nan.series = vec![
            Series::line("nan", vec![(f64::NAN, f64::NAN); 5], LineStyle::Dashed, Color::RED),
            Series::markers("", vec![(1.0, f64::INFINITY)], MarkerShape::Square, Color::BLACK),
        ];
        let mut single = Panel::new("single point", "x", "y");
        single.series = vec![Series::markers("one", vec![(2.0, 3.0)], MarkerShape::Triangle, Color::BLUE)];
        let mut bad_range = Panel::new("bad range", "x", "y");
        bad_range.x_range = Some((1.0, 1.0));
        bad_range.y_range = Some((f64::NAN, 1.0));
        bad_range.series = vec![Series::line(
            "tiny",
            vec![(0.0, 1e-7), (1.0, 3e-7), (2.0, 2e-7)],
            LineStyle::Solid,
            Color::GREEN,
        )];
        let figs = [
            Figure::default(),
            Figure {
                title: "degenerate".into(),
                panels: vec![all_nan, single, bad_range, Panel::default()],
                note: None,
            },
        ];
        for fig in &figs {
            write_figure(fig, &png, &svg).unwrap();
            assert_eq!(png_size(&fs::read(&png).unwrap()), fig.size());
        }
    }

    #[test]
    fn plot_missing_folder_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no/such/folder");
        let png = missing.join("x.png");
        let svg = dir.path().join("x.svg");
        let e = write_figure(&demo_figure(), &png, &svg).unwrap_err();
        assert!(matches!(e, PlotError::Io { .. }), "{e:?}");
        assert!(e.to_string().contains(&png.display().to_string()), "{e}");

        let svg = missing.join("x.svg");
        let png = dir.path().join("x.png");
        let e = write_figure(&demo_figure(), &png, &svg).unwrap_err();
        assert!(e.to_string().contains(&svg.display().to_string()), "{e}");
    }

    #[test]
    fn plot_tick_format() {
        let f = TickFormat::for_range(0.0, 1.0, 6);
        assert_eq!(f.format(0.2), "0.2");
        let f = TickFormat::for_range(0.0, 100.0, 6);
        assert_eq!(f.format(40.0), "40");
        let f = TickFormat::for_range(-0.1, 0.1, 8);
        assert_eq!(f.format(-0.0), "0.00");
        assert!(TickFormat::for_range(0.0, 1e-6, 6).scientific);
        assert!(TickFormat::for_range(0.0, 1e7, 6).scientific);
    }

    #[test]
    fn plot_clipping_breaks_lines() {
        let pts = [(0.0, 0.0), (1.0, 1.0), (f64::NAN, 0.0), (2.0, 0.0), (3.0, 5.0), (4.0, 0.0)];
        let runs = line_runs(&pts, (-10.0, 10.0), (-1.0, 2.0));
        assert_eq!(runs.len(), 3, "{runs:?}");
        assert_eq!(runs[0], vec![(0.0, 0.0), (1.0, 1.0)]);
        assert_eq!(runs[1], vec![(2.0, 0.0), (2.4, 2.0)]);
        assert_eq!(runs[2], vec![(3.6, 2.0), (4.0, 0.0)]);
    }
}
