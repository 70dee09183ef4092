//! The study's pictures: `study.png`, error against time on log-log axes,
//! one series per method (and per family of candidates) with the Pareto
//! front marked, for the lit pixels and for the penumbra; and `crops.png`, the same penumbra crop from the
//! reference and from each method's most accurate run (a light-mesh
//! method's run at the default lattice before it), side by side.
//!
//! Both are drawn with `plotters` into an RGB buffer, labelled with an
//! embedded font (no system font library), and written atomically.

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use super::candidate::Candidate;
use super::measure::Reference;
use super::sweep::{pareto_front, RunResult, Source};
use crate::output::{tone_map, write_srgb_png, Image, OutputError};
use crate::settings::Method;

const FAMILY: &str = "sans-serif";

/// Why a picture could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("{path}: cannot draw: {fault}")]
    Draw { path: String, fault: String },
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Each method's colour, the same in both pictures.
fn colour(method: Method) -> RGBColor {
    match method {
        Method::Auto => RGBColor(148, 103, 189),
        Method::Whitted => RGBColor(90, 90, 90),
        Method::Lmm => RGBColor(31, 119, 180),
        Method::Lmm1 => RGBColor(44, 160, 44),
        Method::Area => RGBColor(214, 39, 40),
    }
}

/// The candidates' families' colours, in the order they first appear.
const CANDIDATE_COLOURS: [RGBColor; 5] = [
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
];

/// One series of points in both panels: its legend and colour, and which
/// runs it draws.
struct Series {
    label: String,
    colour: RGBColor,
    runs: Vec<usize>,
}

/// A series per method of `methods` (in that order), then one per family
/// of candidates (`Candidate::family`, in the order they first appear).
fn series(runs: &[RunResult], methods: &[Method]) -> Vec<Series> {
    let mut all: Vec<Series> = methods
        .iter()
        .map(|&method| Series {
            label: method.to_string(),
            colour: colour(method),
            runs: (runs.iter().enumerate())
                .filter(|(_, run)| run.method() == Some(method))
                .map(|(index, _)| index)
                .collect(),
        })
        .collect();
    let mut families: Vec<Series> = Vec::new();
    for (index, run) in runs.iter().enumerate() {
        let Source::Candidate(name) = &run.source else {
            continue;
        };
        let family = Candidate::family(name);
        match families.iter_mut().find(|series| series.label == family) {
            Some(series) => series.runs.push(index),
            None => families.push(Series {
                label: family.to_owned(),
                colour: CANDIDATE_COLOURS[families.len() % CANDIDATE_COLOURS.len()],
                runs: vec![index],
            }),
        }
    }
    all.extend(families);
    all
}

fn use_embedded_font() {
    // Registering again replaces the same font: harmless.
    let _ = register_font(FAMILY, FontStyle::Normal, crate::output::FONT);
}

/// Draws `study.png`: two log-log panels, lit RMSE and penumbra RMSE
/// against seconds per frame.
pub fn error_against_time(
    path: &std::path::Path,
    runs: &[RunResult],
    methods: &[Method],
) -> Result<(), PlotError> {
    use_embedded_font();
    let (width, height) = (1400u32, 620u32);
    let mut rgb = vec![255u8; (width * height * 3) as usize];
    let fault = |error: &dyn std::fmt::Display| PlotError::Draw {
        path: path.display().to_string(),
        fault: error.to_string(),
    };
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fault(&e))?;
        let panels = root.split_evenly((1, 2));
        let measures: [(&str, Measure); 2] = [
            ("relative RMSE, lit pixels", |run| Some(run.errors.rmse)),
            ("relative RMSE, penumbra pixels", |run| {
                run.errors.penumbra_rmse
            }),
        ];
        let series = series(runs, methods);
        for (panel, (title, measure)) in panels.iter().zip(measures) {
            let points: Vec<Option<(f64, f64)>> = runs
                .iter()
                .map(|run| Some((run.seconds.max(1e-4), measure(run)?.max(1e-5))))
                .collect();
            draw_panel(panel, title, &points, &series).map_err(|e| fault(&e))?;
        }
        root.present().map_err(|e| fault(&e))?;
    }
    Ok(write_srgb_png(path, width, height, &rgb)?)
}

/// What a panel plots of a run (None: the run has no such error).
type Measure = fn(&RunResult) -> Option<f64>;

type Panel<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;
type DrawResult =
    Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

/// Draws one panel; `points[i]` is run i's (seconds, error), None where
/// it has no such error.
fn draw_panel(
    panel: &Panel,
    title: &str,
    points: &[Option<(f64, f64)>],
    series: &[Series],
) -> DrawResult {
    let drawn: Vec<(f64, f64)> = points.iter().flatten().copied().collect();
    let range = |values: Vec<f64>| {
        let low = values.iter().copied().fold(f64::INFINITY, f64::min);
        let high = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if low.is_finite() {
            (low / 1.5)..(high * 1.5)
        } else {
            0.01..1.0
        }
    };
    let x = range(drawn.iter().map(|p| p.0).collect());
    let y = range(drawn.iter().map(|p| p.1).collect());
    let mut chart = ChartBuilder::on(panel)
        .caption(title, (FAMILY, 22))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(70)
        .build_cartesian_2d(x.log_scale(), y.log_scale())?;
    chart
        .configure_mesh()
        .x_desc("seconds per frame")
        .y_desc("relative RMSE")
        .x_label_formatter(&|value| short_number(*value))
        .y_label_formatter(&|value| short_number(*value))
        .light_line_style(RGBColor(238, 238, 238))
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .draw()?;
    for series in series {
        let colour = series.colour;
        let at: Vec<(f64, f64)> = series.runs.iter().filter_map(|&i| points[i]).collect();
        chart
            .draw_series(at.iter().map(|&at| Circle::new(at, 4, colour.filled())))?
            .label(series.label.clone())
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, colour.filled()));
    }
    let mut front: Vec<(f64, f64)> = pareto_front(&drawn)
        .into_iter()
        .zip(&drawn)
        .filter_map(|(on, &at)| on.then_some(at))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(1)))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK));
    chart.draw_series(
        front
            .iter()
            .map(|&at| Circle::new(at, 8, BLACK.stroke_width(1))),
    )?;
    chart
        .configure_series_labels()
        .label_font((FAMILY, 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    Ok(())
}

/// A tick label: three significant digits, no float noise.
fn short_number(value: f64) -> String {
    let digits = (2 - value.abs().log10().floor() as i32).max(0) as usize;
    format!("{value:.digits$}")
}

/// One panel of `crops.png`: a frame and the two lines that name it.
pub struct Crop<'a> {
    pub image: &'a Image,
    pub title: String,
    pub figures: String,
}

/// Draws `crops.png`: the square window of the frame that holds the most
/// penumbra pixels, cut from each of `crops` and enlarged without
/// smoothing, side by side under their labels.
pub fn penumbra_crops(
    path: &std::path::Path,
    reference: &Reference,
    crops: &[Crop],
) -> Result<(), PlotError> {
    use_embedded_font();
    let window = penumbra_window(reference);
    let zoom = (200 / window.side).max(1);
    let (gap, label) = (12u32, 46u32);
    let panel = window.side * zoom;
    let count = crops.len() as u32;
    let (width, height) = (count * panel + (count + 1) * gap, panel + label + 2 * gap);
    let mut rgb = vec![255u8; (width * height * 3) as usize];
    let fault = |error: &dyn std::fmt::Display| PlotError::Draw {
        path: path.display().to_string(),
        fault: error.to_string(),
    };
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        for (index, crop) in crops.iter().enumerate() {
            let left = gap + index as u32 * (panel + gap);
            let top = gap + label;
            let font = (FAMILY, 15).into_font().color(&BLACK);
            for (line, text) in [&crop.title, &crop.figures].into_iter().enumerate() {
                let at = (left as i32, (gap + line as u32 * 20) as i32);
                root.draw(&Text::new(text.as_str(), at, font.clone()))
                    .map_err(|e| fault(&e))?;
            }
            for y in 0..panel {
                for x in 0..panel {
                    let source = crop
                        .image
                        .pixel(window.left + x / zoom, window.top + y / zoom);
                    let [r, g, b, _] = tone_map(source);
                    root.draw_pixel(((left + x) as i32, (top + y) as i32), &RGBColor(r, g, b))
                        .map_err(|e| fault(&e))?;
                }
            }
        }
        root.present().map_err(|e| fault(&e))?;
    }
    Ok(write_srgb_png(path, width, height, &rgb)?)
}

/// A square of the frame, in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    pub left: u32,
    pub top: u32,
    pub side: u32,
}

/// The square (a third of the frame's height, at most 96 pixels) holding
/// the most penumbra pixels; the first such from the top left.
pub fn penumbra_window(reference: &Reference) -> Window {
    let (width, height) = (reference.image.width, reference.image.height);
    let side = (height / 3).clamp(1, 96).min(width);
    // Summed-area table of the penumbra mask, one row and column of
    // zeros ahead.
    let stride = width as usize + 1;
    let mut sums = vec![0u32; stride * (height as usize + 1)];
    for y in 0..height as usize {
        for x in 0..width as usize {
            let here = u32::from(reference.is_penumbra_pixel(y * width as usize + x));
            sums[(y + 1) * stride + x + 1] =
                here + sums[y * stride + x + 1] + sums[(y + 1) * stride + x] - sums[y * stride + x];
        }
    }
    let count = |left: usize, top: usize| {
        let (right, bottom) = (left + side as usize, top + side as usize);
        sums[bottom * stride + right] + sums[top * stride + left]
            - sums[top * stride + right]
            - sums[bottom * stride + left]
    };
    let mut best = (
        0,
        Window {
            left: 0,
            top: 0,
            side,
        },
    );
    for top in 0..=(height - side) as usize {
        for left in 0..=(width - side) as usize {
            let found = count(left, top);
            if found > best.0 {
                best = (
                    found,
                    Window {
                        left: left as u32,
                        top: top as u32,
                        side,
                    },
                );
            }
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use glam::Vec4;

    use super::*;

    #[test]
    fn tick_labels_keep_three_digits() {
        assert_eq!(short_number(0.30000000000000004), "0.300");
        assert_eq!(short_number(0.01), "0.0100");
        assert_eq!(short_number(2.0), "2.00");
        assert_eq!(short_number(150.0), "150");
    }

    #[test]
    fn the_window_finds_the_penumbra() {
        // A 60×30 frame whose penumbra is a 6-pixel-wide band at x 40–45.
        let (width, height) = (60u32, 30u32);
        let flat = Image::filled(width, height, Vec4::ONE);
        let mut reference = flat.clone();
        for y in 0..height {
            for x in 40..46 {
                reference.pixels[(y * width + x) as usize] = Vec4::splat(0.5);
            }
        }
        let measure = Reference::new(reference, &flat, &flat, None).unwrap();
        let window = penumbra_window(&measure);
        assert_eq!(window.side, 10);
        assert!(
            window.left <= 40 && window.left + window.side >= 46,
            "{window:?}"
        );
    }
}
