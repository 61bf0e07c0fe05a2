//! PNG plots of analysis results (plotters, bitmap backend): line charts (discrepancy
//! curves on log-log axes, RAPSD, anisotropy), spectrum images, point sets and per-face
//! maps of planar meshes.
//!
//! Text is drawn with ab_glyph from a TrueType font read at runtime: `STRATA_FONT` if
//! set, else DejaVu Sans at its Debian path (package `fonts-dejavu-core`). Without a
//! font, every plot returns [`PlotError::NoFont`]; numbers (JSON) never depend on plots.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use glam::DVec2;
use plotters::prelude::*;
use strata_engine::mesh::TriMesh;

/// Where fonts are looked for, in order (after `STRATA_FONT`).
const FONT_PATHS: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// Font family name the plots use (registered at runtime).
const FAMILY: &str = "sans-serif";

/// Errors of plotting.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// No usable TrueType font was found.
    #[error(
        "no font for plot text: set STRATA_FONT to a .ttf file or install fonts-dejavu-core \
         (looked in {0:?})"
    )]
    NoFont(Vec<PathBuf>),
    /// Drawing or encoding failed.
    #[error("plot {path}: {message}")]
    Draw {
        /// The output file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// Nothing to plot.
    #[error("plot {0}: no finite data")]
    Empty(PathBuf),
}

/// Registers the font once per process.
fn ensure_font() -> Result<(), PlotError> {
    static FONT: OnceLock<Result<(), Vec<PathBuf>>> = OnceLock::new();
    FONT.get_or_init(|| {
        let mut tried: Vec<PathBuf> = std::env::var_os("STRATA_FONT")
            .map(PathBuf::from)
            .into_iter()
            .collect();
        tried.extend(FONT_PATHS.iter().map(PathBuf::from));
        for path in &tried {
            if let Ok(bytes) = std::fs::read(path) {
                // The font must outlive every plot: leak it once per process.
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font(FAMILY, FontStyle::Normal, bytes).is_ok() {
                    return Ok(());
                }
            }
        }
        Err(tried)
    })
    .clone()
    .map_err(PlotError::NoFont)
}

fn draw_err(path: &Path, e: impl std::fmt::Display) -> PlotError {
    PlotError::Draw {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// One named curve.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
    /// Draw markers at the points as well as the line.
    pub markers: bool,
}

impl Series {
    /// A line through `(x, y)`.
    pub fn line(name: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            name: name.into(),
            x,
            y,
            markers: false,
        }
    }

    /// The same with markers.
    pub fn with_markers(mut self) -> Self {
        self.markers = true;
        self
    }
}

/// Axes of a [`line_chart`].
#[derive(Clone, Debug, Default)]
pub struct Axes {
    /// Chart title.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// Plot log10 of x (label the axis accordingly).
    pub log_x: bool,
    /// Plot log10 of y.
    pub log_y: bool,
    /// Fixed y range (after the log, if any); `None` fits the data.
    pub y_range: Option<(f64, f64)>,
    /// Horizontal reference lines `(y, legend)`, in data units (before the log).
    pub reference: Vec<(f64, String)>,
}

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// A line chart of several series (640 x 420 PNG).
///
/// # Errors
/// [`PlotError`] if no font is found, nothing is finite, or writing fails.
pub fn line_chart(path: &Path, axes: &Axes, series: &[Series]) -> Result<(), PlotError> {
    ensure_font()?;
    let tx = |v: f64| if axes.log_x { v.log10() } else { v };
    let ty = |v: f64| if axes.log_y { v.log10() } else { v };
    let data: Vec<Vec<(f64, f64)>> = series
        .iter()
        .map(|s| {
            s.x.iter()
                .zip(&s.y)
                .map(|(&x, &y)| (tx(x), ty(y)))
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .collect()
        })
        .collect();
    let all: Vec<(f64, f64)> = data.iter().flatten().copied().collect();
    if all.is_empty() {
        return Err(PlotError::Empty(path.to_path_buf()));
    }
    let (mut x0, mut x1) = min_max(all.iter().map(|p| p.0));
    // The fitted range includes the reference lines, so that none is drawn off the chart.
    let (mut y0, mut y1) = axes.y_range.unwrap_or_else(|| {
        min_max(
            all.iter().map(|p| p.1).chain(
                axes.reference
                    .iter()
                    .map(|r| ty(r.0))
                    .filter(|v| v.is_finite()),
            ),
        )
    });
    pad(&mut x0, &mut x1, 0.02);
    if axes.y_range.is_none() {
        pad(&mut y0, &mut y1, 0.05);
    }
    let size: (u32, u32) = (640, 420);
    let mut buf = vec![255u8; 3 * size.0 as usize * size.1 as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&axes.title, (FAMILY, 17))
            .margin(8)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| draw_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc(axes.x_label.as_str())
            .y_desc(axes.y_label.as_str())
            .label_style((FAMILY, 12))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| draw_err(path, e))?;
        for (k, (s, d)) in series.iter().zip(&data).enumerate() {
            let color = COLORS[k % COLORS.len()];
            chart
                .draw_series(LineSeries::new(d.iter().copied(), color.stroke_width(2)))
                .map_err(|e| draw_err(path, e))?
                .label(s.name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2))
                });
            if s.markers {
                chart
                    .draw_series(d.iter().map(|&p| Circle::new(p, 3, color.filled())))
                    .map_err(|e| draw_err(path, e))?;
            }
        }
        for (k, (y, name)) in axes.reference.iter().enumerate() {
            let y = ty(*y);
            let style = RGBColor(90, 90, 90).stroke_width(1);
            let _ = k;
            chart
                .draw_series(DashedLineSeries::new(vec![(x0, y), (x1, y)], 6, 4, style))
                .map_err(|e| draw_err(path, e))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], style));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(180, 180, 180))
            .label_font((FAMILY, 12))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| draw_err(path, e))?;
        root.present().map_err(|e| draw_err(path, e))?;
    }
    encode(path, &buf, size)
}

/// A centred square grid of spectrum values as a grey image (values clamped to
/// `[0, max]`, 0 black), with the frequency extent `+-extent` on both axes.
///
/// # Errors
/// As [`line_chart`].
pub fn spectrum_image(
    path: &Path,
    title: &str,
    values: &[f64],
    side: usize,
    extent: f64,
    max: f64,
) -> Result<(), PlotError> {
    ensure_font()?;
    if side == 0 || values.len() != side * side {
        return Err(PlotError::Empty(path.to_path_buf()));
    }
    let size: (u32, u32) = (360, 380);
    let mut buf = vec![255u8; 3 * size.0 as usize * size.1 as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (FAMILY, 15))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(-extent..extent, -extent..extent)
            .map_err(|e| draw_err(path, e))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .label_style((FAMILY, 11))
            .draw()
            .map_err(|e| draw_err(path, e))?;
        let step = 2.0 * extent / side as f64;
        chart
            .draw_series((0..side * side).map(|i| {
                let (r, c) = (i / side, i % side);
                let v = (values[i] / max).clamp(0.0, 1.0);
                // 32 grey levels: indistinguishable on screen, and the PNG stays small.
                let g = ((v * 31.0).round() * 255.0 / 31.0) as u8;
                let x = -extent + c as f64 * step;
                let y = -extent + r as f64 * step;
                Rectangle::new([(x, y), (x + step, y + step)], RGBColor(g, g, g).filled())
            }))
            .map_err(|e| draw_err(path, e))?;
        root.present().map_err(|e| draw_err(path, e))?;
    }
    encode(path, &buf, size)
}

/// A point set in the rectangle `[0, extent.x] x [0, extent.y]`.
///
/// # Errors
/// As [`line_chart`].
pub fn points(path: &Path, title: &str, points: &[DVec2], extent: DVec2) -> Result<(), PlotError> {
    ensure_font()?;
    let aspect = extent.y / extent.x;
    let w = 420u32;
    let h = ((w as f64 - 40.0) * aspect + 70.0).clamp(150.0, 900.0) as u32;
    let size: (u32, u32) = (w, h);
    let mut buf = vec![255u8; 3 * size.0 as usize * size.1 as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (FAMILY, 15))
            .margin(8)
            .x_label_area_size(24)
            .y_label_area_size(32)
            .build_cartesian_2d(0.0..extent.x, 0.0..extent.y)
            .map_err(|e| draw_err(path, e))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .label_style((FAMILY, 10))
            .draw()
            .map_err(|e| draw_err(path, e))?;
        let dot = if points.len() > 5000 { 1 } else { 2 };
        chart
            .draw_series(
                points
                    .iter()
                    .map(|p| Circle::new((p.x, p.y), dot, BLACK.filled())),
            )
            .map_err(|e| draw_err(path, e))?;
        root.present().map_err(|e| draw_err(path, e))?;
    }
    encode(path, &buf, size)
}

/// A planar mesh (its x, y coordinates) with each face coloured by `values[face]` on a
/// blue (0) to red (`max`) scale; NaN faces grey.
///
/// # Errors
/// As [`line_chart`].
pub fn face_map(
    path: &Path,
    title: &str,
    mesh: &TriMesh,
    values: &[f64],
    max: f64,
) -> Result<(), PlotError> {
    ensure_font()?;
    let (lo, hi) = mesh.bounds();
    let size: (u32, u32) = (460, 440);
    let mut buf = vec![255u8; 3 * size.0 as usize * size.1 as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (FAMILY, 15))
            .margin(8)
            .x_label_area_size(24)
            .y_label_area_size(32)
            .right_y_label_area_size(10)
            .build_cartesian_2d(lo.x..hi.x, lo.y..hi.y)
            .map_err(|e| draw_err(path, e))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .label_style((FAMILY, 10))
            .draw()
            .map_err(|e| draw_err(path, e))?;
        chart
            .draw_series(mesh.triangles().iter().enumerate().map(|(f, t)| {
                let pts: Vec<(f64, f64)> = t
                    .iter()
                    .map(|&v| {
                        let p = mesh.positions()[v as usize];
                        (p.x, p.y)
                    })
                    .collect();
                let v = values.get(f).copied().unwrap_or(f64::NAN);
                Polygon::new(pts, heat(v / max).filled())
            }))
            .map_err(|e| draw_err(path, e))?;
        root.present().map_err(|e| draw_err(path, e))?;
    }
    encode(path, &buf, size)
}

/// Writes an RGB buffer as an indexed-colour PNG, atomically: the 255 most frequent colours form
/// the palette and every other colour takes its nearest palette entry (anti-aliased
/// edges shift slightly; plots stay a few tens of KB).
fn encode(path: &Path, rgb: &[u8], (w, h): (u32, u32)) -> Result<(), PlotError> {
    use std::collections::HashMap;
    let mut counts: HashMap<[u8; 3], usize> = HashMap::new();
    for px in rgb.chunks_exact(3) {
        *counts.entry([px[0], px[1], px[2]]).or_default() += 1;
    }
    let mut by_count: Vec<([u8; 3], usize)> = counts.into_iter().collect();
    by_count.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let palette: Vec<[u8; 3]> = by_count.iter().take(255).map(|c| c.0).collect();
    let mut index_of: HashMap<[u8; 3], u8> = palette
        .iter()
        .enumerate()
        .map(|(i, c)| (*c, i as u8))
        .collect();
    let mut indices = Vec::with_capacity(rgb.len() / 3);
    for px in rgb.chunks_exact(3) {
        let c = [px[0], px[1], px[2]];
        let i = *index_of.entry(c).or_insert_with(|| {
            let d =
                |p: &[u8; 3]| -> i32 { (0..3).map(|k| (p[k] as i32 - c[k] as i32).pow(2)).sum() };
            palette
                .iter()
                .enumerate()
                .min_by_key(|(_, p)| d(p))
                .map_or(0, |(i, _)| i as u8)
        });
        indices.push(i);
    }
    strata_engine::io::write_atomically(path, |file| {
        let mut enc = png::Encoder::new(file, w, h);
        enc.set_color(png::ColorType::Indexed);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_palette(palette.concat());
        enc.set_compression(png::Compression::High);
        let mut writer = enc.write_header()?;
        writer.write_image_data(&indices)?;
        writer.finish()
    })
    .map_err(|e: png::EncodingError| draw_err(path, e))
}

/// Blue (0) to red (1) through white; grey for NaN.
fn heat(t: f64) -> RGBColor {
    if !t.is_finite() {
        return RGBColor(160, 160, 160);
    }
    let t = t.clamp(0.0, 1.0);
    if t < 0.5 {
        let s = t * 2.0;
        RGBColor((60.0 + 195.0 * s) as u8, (90.0 + 165.0 * s) as u8, 255)
    } else {
        let s = (t - 0.5) * 2.0;
        RGBColor(255, (255.0 - 200.0 * s) as u8, (255.0 - 215.0 * s) as u8)
    }
}

fn min_max(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    })
}

fn pad(lo: &mut f64, hi: &mut f64, fraction: f64) {
    let span = (*hi - *lo).abs().max(1e-9);
    *lo -= span * fraction;
    *hi += span * fraction;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Few colours survive the indexed encoding exactly; the file decodes to the image.
    #[test]
    fn indexed_png_round_trips() {
        let (w, h) = (7u32, 5u32);
        let colours = [[255u8, 255, 255], [10, 20, 30], [200, 0, 0]];
        let rgb: Vec<u8> = (0..w * h).flat_map(|i| colours[(i % 3) as usize]).collect();
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("x.png");
        encode(&path, &rgb, (w, h)).expect("encode");
        let mut decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&path).expect("open"),
        ));
        decoder.set_transformations(png::Transformations::EXPAND);
        let mut reader = decoder.read_info().expect("header");
        let mut out = vec![0; reader.output_buffer_size().expect("size")];
        let info = reader.next_frame(&mut out).expect("frame");
        assert_eq!((info.width, info.height), (w, h));
        assert_eq!(&out[..info.buffer_size()], &rgb[..]);
    }

    #[test]
    fn heat_scale_ends() {
        assert_eq!(heat(0.0), RGBColor(60, 90, 255));
        assert_eq!(heat(1.0), RGBColor(255, 55, 40));
        assert_eq!(heat(f64::NAN), RGBColor(160, 160, 160));
    }
}
