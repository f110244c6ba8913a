//! PNG plots with plotters. Text uses DejaVu Sans embedded in the binary (the `dejavu` crate
//! through plotters' `ab_glyph` backend), so no system fonts or fontconfig are needed.

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::path::Path;
use std::sync::Once;

/// Font family name registered for all text.
const FONT: &str = "sans-serif";

fn fonts() {
    static INIT: Once = Once::new();
    INIT.call_once(|| {
        // The font bytes are a valid TTF shipped by the crate; failure would only lose labels.
        let _ = register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
        let _ = register_font(FONT, FontStyle::Bold, dejavu::sans::bold());
    });
}

/// One curve.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text (empty: no legend entry).
    pub label: String,
    /// Points (non-finite ones are skipped).
    pub points: Vec<(f64, f64)>,
    /// Draw markers instead of a line (for sweeps).
    pub markers: bool,
    /// Fixed palette index (one colour per scene across panels); default: the position.
    pub color: Option<usize>,
    /// Dashed line (to tell an estimate or a reference from the truth when they overlap).
    pub dashed: bool,
    /// Line width in pixels (default 1).
    pub width: u32,
}

impl Series {
    /// A line.
    pub fn line(label: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            markers: false,
            color: None,
            dashed: false,
            width: 1,
        }
    }
    /// Line with markers.
    pub fn marked(label: &str, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            markers: true,
            color: None,
            dashed: false,
            width: 1,
        }
    }
    /// Drawn dashed.
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
    /// Drawn `w` pixels wide.
    pub fn width(mut self, w: u32) -> Self {
        self.width = w.max(1);
        self
    }
    /// The same curve in palette colour `i` (the same scene in the same colour on every panel).
    pub fn colored(mut self, i: usize) -> Self {
        self.color = Some(i);
        self
    }
}

/// One chart.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Title.
    pub title: String,
    /// X axis label.
    pub x: String,
    /// Y axis label.
    pub y: String,
    /// Curves.
    pub series: Vec<Series>,
    /// x positions of failed points (drawn as red crosses on the bottom axis, labelled).
    pub failed: Vec<f64>,
}

impl Panel {
    /// A chart.
    pub fn new(title: &str, x: &str, y: &str, series: Vec<Series>) -> Self {
        Self {
            title: title.into(),
            x: x.into(),
            y: y.into(),
            series,
            failed: Vec::new(),
        }
    }

    /// Marks failed points at these x positions.
    pub fn with_failed(mut self, xs: Vec<f64>) -> Self {
        self.failed = xs;
        self
    }
}

/// Palette index of the light grey [`COLORS`] ends with (a transient, a background curve).
pub const GREY: usize = 6;

const COLORS: [RGBColor; 7] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(175, 175, 175),
];

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return (-1.0, 1.0);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.5 * lo.abs().max(1e-12)
    };
    (lo - pad, hi + pad)
}

/// Draws `panels` on a grid of `rows × cols` into a PNG of `width × height` pixels (written
/// beside `path` and renamed into place when complete).
pub fn render(
    path: &Path,
    title: &str,
    panels: &[Panel],
    rows: usize,
    cols: usize,
    size: (u32, u32),
) -> Result<()> {
    crate::output::atomic_with(path, |tmp| {
        draw(tmp, title, panels, rows, cols, size)
            .map_err(|e| anyhow!("plot `{}`: {e:#}", path.display()))
    })
}

fn draw(
    path: &Path,
    title: &str,
    panels: &[Panel],
    rows: usize,
    cols: usize,
    size: (u32, u32),
) -> Result<()> {
    fonts();
    let err = |e: &dyn std::fmt::Display| anyhow!("{e}");
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    // A long title shrinks to fit the width (about 0.55 em per character).
    let title_size = 22.0f64.min(size.0 as f64 / (0.55 * title.chars().count().max(1) as f64));
    let root = root
        .titled(title, (FONT, title_size).into_font().style(FontStyle::Bold))
        .map_err(|e| err(&e))?;
    let areas = root.split_evenly((rows, cols));
    for (panel, area) in panels.iter().zip(areas.iter()) {
        let (x0, x1) = range(
            panel
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.0))
                .chain(panel.failed.iter().copied()),
        );
        let (y0, y1) = range(
            panel
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1)),
        );
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, (FONT, 16))
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(panel.x.as_str())
            .y_desc(panel.y.as_str())
            .label_style((FONT, 12))
            .axis_desc_style((FONT, 13))
            .y_label_formatter(&tick_format(y0, y1))
            .x_label_formatter(&tick_format(x0, x1))
            .draw()
            .map_err(|e| err(&e))?;
        let mut legend = false;
        for (i, s) in panel.series.iter().enumerate() {
            let color = COLORS[s.color.unwrap_or(i) % COLORS.len()];
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .collect();
            let style = color.stroke_width(s.width);
            let anno = if s.dashed {
                chart
                    .draw_series(DashedLineSeries::new(pts.clone(), 6, 4, style))
                    .map_err(|e| err(&e))?
            } else {
                chart
                    .draw_series(LineSeries::new(pts.clone(), style))
                    .map_err(|e| err(&e))?
            };
            if !s.label.is_empty() {
                legend = true;
                let (dashed, w) = (s.dashed, s.width + 1);
                anno.label(s.label.as_str()).legend(move |(x, y)| {
                    // Relative to (x, y): a gap in the middle for a dashed curve.
                    let mid = if dashed { 11 } else { 6 };
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (6, 0)], color.stroke_width(w))
                        + PathElement::new(vec![(mid, 0), (18, 0)], color.stroke_width(w))
                });
            }
            if s.markers {
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
                    .map_err(|e| err(&e))?;
            }
        }
        if !panel.failed.is_empty() {
            let y = y0 + 0.04 * (y1 - y0);
            let mark = BLACK;
            chart
                .draw_series(
                    panel
                        .failed
                        .iter()
                        .filter(|x| x.is_finite())
                        .map(|&x| Cross::new((x, y), 6, mark.stroke_width(3))),
                )
                .map_err(|e| err(&e))?
                .label("failed run (no value)")
                .legend(move |(x, y)| Cross::new((x + 9, y), 5, mark.stroke_width(3)));
            legend = true;
        }
        if legend {
            chart
                .configure_series_labels()
                .label_font((FONT, 12))
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| err(&e))?;
        }
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// One tick format per axis: fixed-point with as many decimals as the axis span needs (a
/// tenth of the span resolved: every tick of an axis has the same number of decimals), or,
/// where the values are beyond 10⁵ or the span below 10⁻⁴, scientific with 3 digits.
pub fn tick_format(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let span = (hi - lo).abs();
    let mag = lo.abs().max(hi.abs());
    let sci = mag >= 1e5 || span < 1e-4;
    let decimals = if span > 0.0 {
        (-(span / 10.0).log10()).ceil().clamp(0.0, 6.0) as usize
    } else {
        2
    };
    move |v: &f64| {
        // Ticks at zero come out as ±1e-16 from the axis arithmetic.
        if v.abs() <= 1e-9 * span {
            "0".into()
        } else if sci {
            format!("{v:.2e}")
        } else {
            format!("{v:.decimals$}")
        }
    }
}
