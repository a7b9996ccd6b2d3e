//! Plots of the experiments' series, as SVG (plotters). SVG keeps the text as text, so no
//! font files are needed to draw the labels.

use std::path::Path;

use plotters::coord::combinators::WithKeyPoints;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::{Error, Result};
use crate::image::write_atomically;

/// One labelled series of (x, y) points.
pub struct Series {
    /// The legend's label.
    pub label: String,
    /// (x, y) points, in order along x.
    pub points: Vec<(f64, f64)>,
}

/// The palette, in order (its first six as before; then pink, grey, olive, cyan, as
/// matplotlib's tab10).
const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// How a series is drawn: points joined by a line or not, markers filled or hollow (a
/// hollow series is joined by a dashed line), in which colour.
#[derive(Clone, Copy, Debug)]
pub struct Marks {
    /// Points joined in order.
    pub joined: bool,
    /// Hollow markers and a dashed line: a second source beside the first (the paper's).
    pub hollow: bool,
    /// The colour's place in the palette; `None`: the series' own place in the plot.
    pub colour: Option<usize>,
}

impl Marks {
    /// Filled markers joined by a line.
    pub const LINE: Marks = Marks {
        joined: true,
        hollow: false,
        colour: None,
    };
    /// Filled markers alone.
    pub const POINTS: Marks = Marks {
        joined: false,
        hollow: false,
        colour: None,
    };
    /// Hollow markers joined by a dashed line.
    pub const HOLLOW: Marks = Marks {
        joined: true,
        hollow: true,
        colour: None,
    };

    /// These marks in the palette's colour `place` (the same thing in the same colour across
    /// plots, whichever series a plot lacks).
    pub const fn coloured(self, place: usize) -> Marks {
        Marks {
            colour: Some(place),
            ..self
        }
    }
}

/// A log-log plot of `series` written to `path` (SVG), each a line through its points. Points
/// with non-positive or non-finite coordinates are left out (they have no place on log axes).
pub fn log_log(path: &Path, title: &str, x_label: &str, y_label: &str, series: &[Series]) -> Result<()> {
    let drawn: Vec<(&Series, Marks)> = series.iter().map(|s| (s, Marks::LINE)).collect();
    log_log_with(path, title, x_label, y_label, &drawn, &[])
}

/// A log-log plot of `ours`, each a line through its points, and beside them `paper`, the
/// paper's values of the same things: `paper[i]` hollow and dashed in `ours[i]`'s colour.
pub fn log_log_beside_paper(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    ours: &[Series],
    paper: &[Series],
) -> Result<()> {
    let drawn: Vec<(&Series, Marks)> = ours
        .iter()
        .enumerate()
        .map(|(i, s)| (s, Marks::LINE.coloured(i)))
        .chain(
            paper
                .iter()
                .enumerate()
                .map(|(i, s)| (s, Marks::HOLLOW.coloured(i))),
        )
        .collect();
    log_log_with(path, title, x_label, y_label, &drawn, &[])
}

/// A log-log plot of `series`, each drawn as its [`Marks`] say, with a front where `front`
/// has points: they are joined (in order along x) by a black staircase (the best y reached by
/// each x), each labelled with its text (an empty text: no label).
pub fn log_log_with(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(&Series, Marks)],
    front: &[(f64, f64, String)],
) -> Result<()> {
    let fail = |e: &dyn std::fmt::Display| Error::file(path, format!("cannot draw the plot: {e}"));
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|(s, _)| s.points.iter().copied().filter(usable))
        .collect();
    if all.is_empty() {
        return Err(Error::parameter(format!("nothing to plot in {}", path.display())));
    }
    // Room left of the data for the front's labels, which sit left of their points.
    let left_room = if front.is_empty() { 1.5 } else { 8.0 };
    let range = |f: fn(&(f64, f64)) -> f64, room: f64| {
        let (lo, hi) = all
            .iter()
            .map(f)
            .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
        (lo / room)..(hi * 1.5)
    };
    let (x_range, y_range) = (range(|p| p.0, left_room), range(|p| p.1, 1.5));
    let legend = emptiest_corner(&all, (x_range.start, x_range.end), (y_range.start, y_range.end));
    let size = if front.is_empty() { (720, 480) } else { (900, 600) };
    let y_ticks = log_ticks(y_range.start, y_range.end);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                x_range.log_scale(),
                y_range.clone().log_scale().with_key_points(y_ticks),
            )
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .light_line_style(WHITE)
            .x_label_formatter(&|v| short(*v))
            .y_label_formatter(&|v| short(*v))
            .draw()
            .map_err(|e| fail(&e))?;
        draw_series(&mut chart, series, path)?;
        if !front.is_empty() {
            draw_front(&mut chart, front, path)?;
        }
        chart
            .configure_series_labels()
            .position(legend)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| fail(&e))?;
        root.present().map_err(|e| fail(&e))?;
    }
    write_atomically(path, svg.as_bytes())
}

/// The chart [`log_log_with`] draws on.
type LogLogChart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<LogCoord<f64>, WithKeyPoints<LogCoord<f64>>>>;

/// Ticks of a log axis from `lo` to `hi`: 1, 2 and 5 times the powers of ten between them,
/// or every digit where those are fewer than three (an axis under a decade otherwise shows
/// one label or none).
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let decades = lo.log10().floor() as i32..=hi.log10().ceil() as i32;
    let ticks = |mantissas: &[f64]| -> Vec<f64> {
        decades
            .clone()
            .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let coarse = ticks(&[1.0, 2.0, 5.0]);
    if coarse.len() >= 3 {
        coarse
    } else {
        ticks(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
    }
}

/// Whether a point can be drawn on log axes.
fn usable(&(x, y): &(f64, f64)) -> bool {
    x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite()
}

/// Each of `series` as its [`Marks`] say, with its legend entry.
fn draw_series<'a, 'b: 'a>(
    chart: &mut LogLogChart<'a, 'b>,
    series: &[(&Series, Marks)],
    path: &Path,
) -> Result<()> {
    let fail = |e: &dyn std::fmt::Display| Error::file(path, format!("cannot draw the plot: {e}"));
    for (place, &(s, marks)) in series.iter().enumerate() {
        let colour = &COLOURS[marks.colour.unwrap_or(place) % COLOURS.len()];
        let points: Vec<(f64, f64)> = s.points.iter().copied().filter(usable).collect();
        let line = colour.stroke_width(if marks.hollow { 1 } else { 2 });
        match (marks.joined, marks.hollow) {
            (true, false) => chart.draw_series(LineSeries::new(points.clone(), line)),
            (true, true) => chart.draw_series(DashedLineSeries::new(points.clone(), 6, 4, line)),
            (false, _) => chart.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>()),
        }
        .map_err(|e| fail(&e))?
        .label(&s.label)
        .legend(move |(x, y)| {
            let dot = Circle::new((10, 0), 3, if marks.hollow { line } else { colour.filled() });
            let stroke = if marks.joined {
                line
            } else {
                colour.mix(0.0).into()
            };
            EmptyElement::at((x, y)) + PathElement::new([(0, 0), (20, 0)], stroke) + dot
        });
        let marker = if marks.hollow {
            colour.stroke_width(1)
        } else {
            colour.filled()
        };
        chart
            .draw_series(
                points
                    .into_iter()
                    .map(|p| Circle::new(p, if marks.hollow { 4 } else { 3 }, marker)),
            )
            .map_err(|e| fail(&e))?;
    }
    Ok(())
}

/// The front: its points joined by a black staircase, each labelled.
fn draw_front<'a, 'b: 'a>(
    chart: &mut LogLogChart<'a, 'b>,
    front: &[(f64, f64, String)],
    path: &Path,
) -> Result<()> {
    let fail = |e: &dyn std::fmt::Display| Error::file(path, format!("cannot draw the plot: {e}"));
    // The staircase: from each front point right to the next one's x, then down to it.
    let mut stairs = vec![(front[0].0, front[0].1)];
    for pair in front.windows(2) {
        stairs.push((pair[1].0, pair[0].1));
        stairs.push((pair[1].0, pair[1].1));
    }
    chart
        .draw_series(LineSeries::new(stairs, BLACK.stroke_width(1)))
        .map_err(|e| fail(&e))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    // Labels below and left of their points: the front falls to the right, so that
    // corner holds no image (one there would be faster and more accurate).
    let font = ("sans-serif", 11)
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Right, VPos::Top));
    chart
        .draw_series(front.iter().map(|(x, y, text)| {
            EmptyElement::at((*x, *y))
                + Circle::new((0, 0), 5, BLACK.stroke_width(1))
                + Text::new(text.clone(), (-5, 5), font.clone())
        }))
        .map_err(|e| fail(&e))?;
    Ok(())
}

/// The corner of a log-log plot over `x` and `y` where the legend covers the fewest of
/// `points` (the first of upper right, upper left, lower right, lower left on a tie).
fn emptiest_corner(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let place = |v: f64, (lo, hi): (f64, f64)| (v / lo).ln() / (hi / lo).ln();
    // The legend's box, as fractions of the plot: 40 % wide, 30 % high.
    let corners = [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ];
    let covered = |right: bool, upper: bool| {
        points
            .iter()
            .filter(|&&(px, py)| {
                let (u, v) = (place(px, x), place(py, y));
                (if right { u > 0.6 } else { u < 0.4 }) && (if upper { v > 0.7 } else { v < 0.3 })
            })
            .count()
    };
    corners
        .into_iter()
        .min_by_key(|&(_, right, upper)| covered(right, upper))
        .map_or(SeriesLabelPosition::UpperRight, |(corner, _, _)| corner)
}

/// A tick label without float noise: 3 significant digits.
fn short(v: f64) -> String {
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

#[cfg(test)]
mod tests {
    use super::log_ticks;

    #[test]
    fn log_ticks_are_one_two_five_or_every_digit_under_a_decade() {
        let close = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x / y - 1.0).abs() < 1e-12)
        };
        let t = log_ticks(1.5, 15.0);
        assert!(close(&t, &[2.0, 5.0, 10.0]), "{t:?}");
        let t = log_ticks(0.009, 0.3);
        assert!(close(&t, &[0.01, 0.02, 0.05, 0.1, 0.2]), "{t:?}");
        // Under a decade with fewer than three of 1, 2, 5: every digit.
        let t = log_ticks(1.2, 4.5);
        assert!(close(&t, &[2.0, 3.0, 4.0]), "{t:?}");
    }
}
