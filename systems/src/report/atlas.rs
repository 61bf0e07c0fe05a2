//! Pictures of parameterizations: every segment's uv layout as one tile of an SVG atlas,
//! for a person to look at.
//!
//! Input: a mesh, its tensor field and the segments' [`SegmentParam`]s (segment id =
//! index in the slice). Output: SVG text (or a file, written atomically). Each tile
//! shows the segment's [`to_unit_square`](SegmentParam::to_unit_square) layout (aspect
//! kept, centred, `v` pointing up), its triangles as thin grey outlines over a light
//! per-segment colour (red-tinted when the report says invalid), flipped triangles
//! filled red, boundary edges darker, and the id and the report's numbers as a caption.
//!
//! Per triangle a short tick (`<line class="tick">`) sits at the uv centroid along the
//! *mapped* major direction: the image of the face's major eigenvector (at the
//! barycentre) under the linear map that takes the triangle's 3D edge vectors, written
//! in a frame of the face plane, to its uv edge vectors. A field-aligned
//! parameterization therefore shows every tick horizontal.
//!
//! Size limits: at most [`MAX_SEGMENTS`] tiles (the title says how many were left
//! out), and at most [`MAX_TICKS_PER_SEGMENT`] ticks per tile: a segment with more
//! triangles gets a tick on every `k`-th triangle only, `k = ceil(triangles /
//! MAX_TICKS_PER_SEGMENT)` (the caption says `ticks 1/k`). All triangles are drawn.
//! Coordinates are pixels with at most 2 decimals.
//!
//! Cost: O(triangles) time; about 50 bytes of output per triangle and 60 per tick.

use std::cmp::Ordering;
use std::fmt::Write as _;
use std::path::Path;

use glam::{DVec2, DVec3};
use strata_engine::field::{TensorField, tangent_frame};
use strata_engine::mesh::TriMesh;
use strata_engine::param::SegmentParam;
use strata_engine::param::predicates::orient2d;

/// Most segments drawn; the rest are counted in the title but get no tile.
pub const MAX_SEGMENTS: usize = 2000;

/// Most ticks drawn per segment; larger segments get a tick on every `k`-th triangle.
pub const MAX_TICKS_PER_SEGMENT: usize = 3000;

/// Side of a tile's square drawing area, margins included (px).
const TILE_PX: f64 = 240.0;
/// Margin between the layout and the edge of the drawing area (px).
const MARGIN_PX: f64 = 10.0;
/// Height of the caption above the drawing area (px).
const HEADER_PX: f64 = 44.0;
/// Gap between tiles and around the grid (px).
const GAP_PX: f64 = 8.0;
/// Height of the title line above the grid (px).
const TITLE_PX: f64 = 24.0;
/// Tick length as a fraction of the drawing area: 0.8 x the mean spacing of the drawn
/// ticks, clamped to this range.
const TICK_FRACTION: (f64, f64) = (0.01, 0.05);

/// Writes [`atlas_svg`] to `path` atomically
/// ([`strata_engine::io::write_atomically`]).
pub fn write_atlas_svg(
    path: &Path,
    mesh: &TriMesh,
    field: &TensorField,
    params: &[SegmentParam],
) -> std::io::Result<()> {
    let svg = atlas_svg(mesh, field, params);
    strata_engine::io::write_atomically(path, |w| std::io::Write::write_all(w, svg.as_bytes()))
}

/// The atlas of `params` as SVG text (see the [module docs](self)): tiles in a grid of
/// `ceil(sqrt(n))` columns, segment `i` in tile `i` (row-major), at most
/// [`MAX_SEGMENTS`] of them. Elements carry classes for tools and tests: `tile` (a
/// tile's frame `<rect>`, plus `invalid` for invalid segments), `tri` (all triangles
/// of a tile as one `<path>`), `flip` (flipped triangles), `bnd` (boundary edges) and
/// `tick` (one `<line>` per ticked triangle).
///
/// ```
/// use strata_engine::{field::FieldSpec, mesh::shapes, param};
/// use strata_systems::report::atlas::atlas_svg;
/// let mesh = shapes::plane(1.0, 4)?;
/// let spec = FieldSpec::Constant { direction: [1.0, 1.0, 0.0], anisotropy: 2.0, density: 1.0 };
/// let field = spec.build(&mesh)?;
/// let faces: Vec<u32> = (0..mesh.face_count() as u32).collect();
/// let cut = vec![false; mesh.edge_count()];
/// let p = param::parameterize(&mesh, &field, &faces, &cut, &param::ParamOptions::default())?;
/// let svg = atlas_svg(&mesh, &field, &[p]);
/// assert!(svg.starts_with("<svg") && svg.matches("class=\"tick\"").count() == 32);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn atlas_svg(mesh: &TriMesh, field: &TensorField, params: &[SegmentParam]) -> String {
    let drawn = params.len().min(MAX_SEGMENTS);
    let mut cols = 1;
    while cols * cols < drawn {
        cols += 1;
    }
    let rows = drawn.div_ceil(cols);
    let tile_w = TILE_PX;
    let tile_h = HEADER_PX + TILE_PX;
    let width = (GAP_PX + cols as f64 * (tile_w + GAP_PX)).max(480.0);
    let height = TITLE_PX + GAP_PX + rows as f64 * (tile_h + GAP_PX);

    let mut out = String::with_capacity(
        4096 + params[..drawn]
            .iter()
            .map(|p| 1024 + 110 * p.triangles.len())
            .sum::<usize>(),
    );
    out.push_str("<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 ");
    push_num(&mut out, width);
    out.push(' ');
    push_num(&mut out, height);
    out.push_str("\" width=\"");
    push_num(&mut out, width);
    out.push_str("\" height=\"");
    push_num(&mut out, height);
    out.push_str("\">\n");
    out.push_str(
        "<style>\
         text{font-family:sans-serif;fill:#222}\
         .title{font-size:14px;font-weight:bold}\
         .label{font-size:11px;font-weight:bold}\
         .caption{font-size:9.5px}\
         .bad{fill:#c00000}\
         .tile{fill:#ffffff;stroke:#b8b8b8;stroke-width:1}\
         .tile.invalid{fill:#fff1f1;stroke:#d02020}\
         .tri{stroke:#8c8c8c;stroke-width:0.3;stroke-linejoin:round}\
         .flip{fill:#e02020;stroke:none}\
         .bnd{fill:none;stroke:#303030;stroke-width:0.9;stroke-linecap:round}\
         .tick{stroke:#0b3d91;stroke-width:0.7;stroke-linecap:round}\
         </style>\n",
    );
    out.push_str("<rect width=\"100%\" height=\"100%\" fill=\"#f4f4f4\"/>\n");

    let valid = params.iter().filter(|p| p.report.valid).count();
    let triangles: usize = params.iter().map(|p| p.triangles.len()).sum();
    out.push_str("<text class=\"title\" x=\"");
    push_num(&mut out, GAP_PX);
    out.push_str("\" y=\"");
    push_num(&mut out, TITLE_PX - 6.0);
    let _ = write!(
        out,
        "\">uv atlas: {} segments ({valid} valid), {triangles} triangles",
        params.len()
    );
    if drawn < params.len() {
        let _ = write!(out, "; first {drawn} drawn");
    }
    out.push_str("</text>\n");

    for (id, param) in params[..drawn].iter().enumerate() {
        let origin = DVec2::new(
            GAP_PX + (id % cols) as f64 * (tile_w + GAP_PX),
            TITLE_PX + GAP_PX + (id / cols) as f64 * (tile_h + GAP_PX),
        );
        push_tile(&mut out, mesh, field, id, param, origin);
    }
    out.push_str("</svg>\n");
    out
}

/// Appends one segment's tile, its top-left corner at `origin` (px).
fn push_tile(
    out: &mut String,
    mesh: &TriMesh,
    field: &TensorField,
    id: usize,
    param: &SegmentParam,
    origin: DVec2,
) {
    let n = param.triangles.len();
    let tick_step = n.div_ceil(MAX_TICKS_PER_SEGMENT).max(1);
    let _ = writeln!(out, "<g id=\"segment-{id}\">");
    push_tile_header(out, id, param, origin, tick_step);
    if n > 0 {
        let layout = TileLayout::new(param, origin);
        push_tile_paths(out, id, param, &layout.coords);
        push_ticks(out, mesh, field, param, &layout, tick_step);
    }
    out.push_str("</g>\n");
}

/// A tile's frame and its three lines of text: the segment's name, size and validity,
/// its angles and anisotropy, and its flips, overlap, fallback and tick thinning.
fn push_tile_header(
    out: &mut String,
    id: usize,
    param: &SegmentParam,
    origin: DVec2,
    tick_step: usize,
) {
    let report = &param.report;
    let n = param.triangles.len();
    out.push_str("<rect class=\"tile");
    if !report.valid {
        out.push_str(" invalid");
    }
    out.push_str("\" x=\"");
    push_num(out, origin.x);
    out.push_str("\" y=\"");
    push_num(out, origin.y);
    out.push_str("\" width=\"");
    push_num(out, TILE_PX);
    out.push_str("\" height=\"");
    push_num(out, HEADER_PX + TILE_PX);
    out.push_str("\"/>\n");

    let text_x = origin.x + 6.0;
    push_text_open(out, "label", text_x, origin.y + 14.0);
    let _ = write!(out, "segment {id} \u{b7} {n} triangles \u{b7} ");
    if report.valid {
        out.push_str("valid");
    } else {
        out.push_str("<tspan class=\"bad\">invalid</tspan>");
    }
    out.push_str("</text>\n");
    push_text_open(out, "caption", text_x, origin.y + 27.0);
    let _ = write!(
        out,
        "angle mean {:.2}\u{b0} max {:.2}\u{b0} \u{b7} anisotropy {:.2}",
        report.mean_angle_deg, report.max_angle_deg, report.mean_anisotropy
    );
    out.push_str("</text>\n");
    push_text_open(out, "caption", text_x, origin.y + 39.0);
    let flag = |b: bool| if b { "yes" } else { "no" };
    let _ = write!(
        out,
        "flips {} \u{b7} overlap {} \u{b7} fallback {}",
        report.flipped,
        flag(report.overlaps),
        flag(report.isotropic_fallback)
    );
    if tick_step > 1 {
        let _ = write!(out, " \u{b7} ticks 1/{tick_step}");
    }
    out.push_str("</text>\n");
}

/// Where a segment's parameterization is drawn in its tile: the unit-square layout,
/// centred in the drawing area, v up.
struct TileLayout {
    /// The vertices in the unit square.
    unit: Vec<DVec2>,
    /// The vertices in pixels.
    px: Vec<DVec2>,
    /// The vertices as SVG coordinates (`x y`).
    coords: Vec<String>,
    /// Side of the drawing area in pixels.
    inner: f64,
}

impl TileLayout {
    fn new(param: &SegmentParam, origin: DVec2) -> Self {
        let (unit, _, _) = param.to_unit_square();
        let extent = unit
            .iter()
            .fold(DVec2::ZERO, |hi, p| hi.max(*p))
            .min(DVec2::ONE);
        let pad = (DVec2::ONE - extent) * 0.5;
        let inner = TILE_PX - 2.0 * MARGIN_PX;
        let corner = origin + DVec2::new(MARGIN_PX, HEADER_PX + MARGIN_PX);
        let to_px = |p: DVec2| corner + DVec2::new(p.x + pad.x, 1.0 - (p.y + pad.y)) * inner;
        let px: Vec<DVec2> = unit.iter().map(|p| to_px(*p)).collect();
        let coords: Vec<String> = px
            .iter()
            .map(|p| {
                let mut s = String::with_capacity(16);
                push_num(&mut s, p.x);
                s.push(' ');
                push_num(&mut s, p.y);
                s
            })
            .collect();
        Self {
            unit,
            px,
            coords,
            inner,
        }
    }
}

/// A tile's triangles (filled in the segment's colour), its flipped triangles and its
/// boundary, as SVG paths over the vertices' `coords`.
fn push_tile_paths(out: &mut String, id: usize, param: &SegmentParam, coords: &[String]) {
    let push_triangle = |out: &mut String, t: &[u32; 3]| {
        out.push('M');
        out.push_str(&coords[t[0] as usize]);
        out.push('L');
        out.push_str(&coords[t[1] as usize]);
        out.push('L');
        out.push_str(&coords[t[2] as usize]);
        out.push('Z');
    };

    let fill = segment_fill(id, param.report.valid);
    let _ = write!(out, "<path class=\"tri\" fill=\"{fill}\" d=\"");
    for t in &param.triangles {
        push_triangle(out, t);
    }
    out.push_str("\"/>\n");

    // The same exact predicate as the report's flip count.
    let flipped: Vec<&[u32; 3]> = param
        .triangles
        .iter()
        .filter(|t| {
            let q = t.map(|v| param.uv[v as usize]);
            orient2d(q[0], q[1], q[2]) != Ordering::Greater
        })
        .collect();
    if !flipped.is_empty() {
        out.push_str("<path class=\"flip\" d=\"");
        for t in flipped {
            push_triangle(out, t);
        }
        out.push_str("\"/>\n");
    }

    out.push_str("<path class=\"bnd\" d=\"");
    for [a, b] in param.boundary_edges() {
        out.push('M');
        out.push_str(&coords[a as usize]);
        out.push('L');
        out.push_str(&coords[b as usize]);
    }
    out.push_str("\"/>\n");
}

/// The field's major direction as a tick at the centroid of every `tick_step`-th
/// triangle of a tile.
fn push_ticks(
    out: &mut String,
    mesh: &TriMesh,
    field: &TensorField,
    param: &SegmentParam,
    layout: &TileLayout,
    tick_step: usize,
) {
    let n = param.triangles.len();
    // One tick length per tile: 0.8 x the mean spacing of the drawn ticks over the
    // layout's area, so small segments get visible ticks and big ones no hairball.
    let area_unit: f64 = param
        .triangles
        .iter()
        .map(|t| {
            let q = t.map(|v| layout.unit[v as usize]);
            0.5 * (q[1] - q[0]).perp_dot(q[2] - q[0]).abs()
        })
        .sum();
    let ticks = n.div_ceil(tick_step);
    let fraction =
        (0.8 * (area_unit / ticks as f64).sqrt()).clamp(TICK_FRACTION.0, TICK_FRACTION.1);
    let half = 0.5 * fraction * layout.inner;
    let px = &layout.px;
    out.push_str("<g class=\"ticks\">\n");
    for i in (0..n).step_by(tick_step) {
        let Some(dir) = mapped_major(mesh, field, param, i) else {
            continue;
        };
        let t = param.triangles[i];
        let centroid = (px[t[0] as usize] + px[t[1] as usize] + px[t[2] as usize]) / 3.0;
        // Both ends from the rounded centroid: a horizontal tick then prints the same
        // y twice, whatever the rounding of the centroid.
        let c = (centroid * 100.0).round() / 100.0;
        let h = DVec2::new(dir.x, -dir.y) * half;
        out.push_str("<line class=\"tick\" x1=\"");
        push_num(out, c.x - h.x);
        out.push_str("\" y1=\"");
        push_num(out, c.y - h.y);
        out.push_str("\" x2=\"");
        push_num(out, c.x + h.x);
        out.push_str("\" y2=\"");
        push_num(out, c.y + h.y);
        out.push_str("\"/>\n");
    }
    out.push_str("</g>\n");
}

/// Unit direction, in `uv` (v up), of the image of face `param.faces[i]`'s major
/// eigenvector (at the barycentre) under the triangle's linear map from its 3D edge
/// vectors (in a frame of the face plane) to its `uv` edge vectors. `None` for a
/// degenerate triangle in 3D or a zero image.
fn mapped_major(
    mesh: &TriMesh,
    field: &TensorField,
    param: &SegmentParam,
    i: usize,
) -> Option<DVec2> {
    let f = param.faces[i];
    let t = param.triangles[i];
    let p = t.map(|v| mesh.positions()[param.local_to_mesh[v as usize] as usize]);
    let q = t.map(|v| param.uv[v as usize]);
    let (t1, t2) = tangent_frame(mesh.face_normals()[f as usize]);
    let flat = |d: DVec3| DVec2::new(d.dot(t1), d.dot(t2));
    let (e1, e2) = (flat(p[1] - p[0]), flat(p[2] - p[0]));
    let m = flat(field.face_eigen(mesh, f, [1.0 / 3.0; 3]).major);
    let det = e1.perp_dot(e2);
    if !(det.abs() > 1e-14 * e1.length_squared().max(e2.length_squared())) {
        return None;
    }
    // m = a e1 + b e2 (Cramer's rule); the map sends e1, e2 to the uv edges.
    let a = m.perp_dot(e2) / det;
    let b = e1.perp_dot(m) / det;
    let image = (q[1] - q[0]) * a + (q[2] - q[0]) * b;
    let length = image.length();
    (length > 0.0 && length.is_finite()).then(|| image / length)
}

/// `<text class="{class}" x=".." y="..">` (the caller closes it).
fn push_text_open(out: &mut String, class: &str, x: f64, y: f64) {
    let _ = write!(out, "<text class=\"{class}\" x=\"");
    push_num(out, x);
    out.push_str("\" y=\"");
    push_num(out, y);
    out.push_str("\">");
}

/// Appends `x` with at most 2 decimals and no trailing zeros (`-0` and non-finite
/// values print as `0`).
fn push_num(out: &mut String, x: f64) {
    let r = if x.is_finite() {
        (x * 100.0).round() / 100.0
    } else {
        0.0
    };
    let r = if r == 0.0 { 0.0 } else { r };
    let start = out.len();
    let _ = write!(out, "{r:.2}");
    if out[start..].contains('.') {
        while out.ends_with('0') {
            out.pop();
        }
        if out.ends_with('.') {
            out.pop();
        }
    }
}

/// A fully saturated colour (RGB in [0, 1]) per segment id: hues in golden-ratio steps,
/// so that neighbouring ids look different. Shared by the atlas and the coloured mesh.
pub fn segment_hue(id: usize) -> [f64; 3] {
    let hue = (id as f64 * 0.618_033_988_749_895).fract() * 6.0;
    let x = 1.0 - (hue % 2.0 - 1.0).abs();
    match hue as u32 {
        0 => [1.0, x, 0.0],
        1 => [x, 1.0, 0.0],
        2 => [0.0, 1.0, x],
        3 => [0.0, x, 1.0],
        4 => [x, 0.0, 1.0],
        _ => [1.0, 0.0, x],
    }
}

/// A light colour per segment id (golden-ratio hue steps), mixed with red for invalid
/// segments, as `#rrggbb`.
fn segment_fill(id: usize, valid: bool) -> String {
    // Pastel: mostly white with a touch of the hue.
    let mut rgb = segment_hue(id).map(|c| 0.8 + 0.2 * c);
    if !valid {
        let red = [1.0, 0.45, 0.45];
        for (c, t) in rgb.iter_mut().zip(red) {
            *c = 0.4 * *c + 0.6 * t;
        }
    }
    let [r, g, b] = rgb.map(|c| (255.0 * c).round().clamp(0.0, 255.0) as u8);
    format!("#{r:02x}{g:02x}{b:02x}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use strata_engine::fixtures::{constant, field_on};

    use glam::DQuat;
    use strata_engine::mesh::shapes;
    use strata_engine::param::{ParamOptions, parameterize};

    /// One tag of the SVG: its name, whether it closes (`</g>`) or is empty (`<x/>`),
    /// and its attribute text.
    struct Tag<'a> {
        name: &'a str,
        closing: bool,
        empty: bool,
        text: &'a str,
    }

    impl Tag<'_> {
        fn attr(&self, name: &str) -> Option<&str> {
            let key = format!(" {name}=\"");
            let start = self.text.find(&key)? + key.len();
            let len = self.text[start..].find('"')?;
            Some(&self.text[start..start + len])
        }

        fn num(&self, name: &str) -> f64 {
            self.attr(name)
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| panic!("numeric attribute {name} in <{}>", self.text))
        }

        fn has_class(&self, class: &str) -> bool {
            self.attr("class")
                .is_some_and(|c| c.split_whitespace().any(|w| w == class))
        }
    }

    /// The tags of `svg`, checked to be well formed enough: every `<` closes with
    /// `>`, no `<` or `&` in text, every start tag is closed in order, one root `svg`.
    fn parse(svg: &str) -> Vec<Tag<'_>> {
        assert!(svg.starts_with("<svg"));
        let mut tags = Vec::new();
        let mut stack: Vec<&str> = Vec::new();
        let mut rest = svg;
        let mut roots = 0;
        while let Some(open) = rest.find('<') {
            assert!(!rest[..open].contains('&') && !rest[..open].contains('>'));
            let close = open + rest[open..].find('>').expect("tag closes");
            let inner = &rest[open + 1..close];
            assert!(!inner.contains('<'), "nested < in {inner}");
            let closing = inner.starts_with('/');
            let empty = inner.ends_with('/');
            let body = inner.trim_start_matches('/').trim_end_matches('/');
            let name = body.split_whitespace().next().expect("tag name");
            if closing {
                assert_eq!(stack.pop(), Some(name), "unbalanced </{name}>");
            } else {
                if stack.is_empty() {
                    roots += 1;
                }
                if !empty {
                    stack.push(name);
                }
            }
            // Quotes come in pairs inside a tag.
            assert_eq!(body.matches('"').count() % 2, 0, "{body}");
            tags.push(Tag {
                name,
                closing,
                empty,
                text: body,
            });
            rest = &rest[close + 1..];
        }
        assert!(stack.is_empty(), "unclosed {stack:?}");
        assert_eq!(rest.trim(), "");
        assert_eq!(roots, 1);
        let root = &tags[0];
        assert_eq!(root.name, "svg");
        assert_eq!(root.attr("xmlns"), Some("http://www.w3.org/2000/svg"));
        let view_box: Vec<f64> = root
            .attr("viewBox")
            .expect("viewBox")
            .split(' ')
            .map(|v| v.parse().expect("number"))
            .collect();
        assert!(view_box.len() == 4 && view_box[2] > 0.0 && view_box[3] > 0.0);
        let opens = tags
            .iter()
            .filter(|t| t.name == "g" && !t.closing && !t.empty)
            .count();
        let closes = tags.iter().filter(|t| t.name == "g" && t.closing).count();
        assert_eq!(opens, closes);
        tags
    }

    /// Ticks as `(x1, y1, x2, y2)`, in document order.
    fn ticks(tags: &[Tag<'_>]) -> Vec<[f64; 4]> {
        tags.iter()
            .filter(|t| t.name == "line" && t.has_class("tick"))
            .map(|t| [t.num("x1"), t.num("y1"), t.num("x2"), t.num("y2")])
            .collect()
    }

    /// `|sin|` of the angle between a tick and the x axis.
    fn sin_to_horizontal([x1, y1, x2, y2]: [f64; 4]) -> f64 {
        (y2 - y1).abs() / (x2 - x1).hypot(y2 - y1)
    }

    fn constant_field(mesh: &TriMesh, direction: [f64; 3]) -> TensorField {
        field_on(mesh, &constant(direction, 3.0))
    }

    fn param_all(mesh: &TriMesh, field: &TensorField) -> SegmentParam {
        param_faces(
            mesh,
            field,
            &(0..mesh.face_count() as u32).collect::<Vec<_>>(),
        )
    }

    fn param_faces(mesh: &TriMesh, field: &TensorField, faces: &[u32]) -> SegmentParam {
        let cut = vec![false; mesh.edge_count()];
        parameterize(mesh, field, faces, &cut, &ParamOptions::default()).expect("param")
    }

    #[test]
    fn plane_constant_field_has_one_horizontal_tick_per_triangle() {
        let mesh = shapes::plane(1.0, 8).expect("plane");
        let field = constant_field(&mesh, [1.0, 0.0, 0.0]);
        let p = param_all(&mesh, &field);
        assert!(p.report.valid);
        let svg = atlas_svg(&mesh, &field, std::slice::from_ref(&p));
        let tags = parse(&svg);
        let ticks = ticks(&tags);
        assert_eq!(ticks.len(), mesh.face_count());
        for t in ticks {
            assert!(sin_to_horizontal(t) <= 1e-6, "{t:?}");
            assert!((t[2] - t[0]).abs() > 1.0, "tick too short: {t:?}");
        }
        let tiles = tags.iter().filter(|t| t.has_class("tile")).count();
        assert_eq!(tiles, 1);
        // No flips, so no flip path; the caption carries the report.
        assert!(!tags.iter().any(|t| t.has_class("flip")));
        assert!(svg.contains("segment 0 \u{b7} 128 triangles \u{b7} valid"));
        assert!(svg.contains("flips 0 \u{b7} overlap no \u{b7} fallback no"));
    }

    #[test]
    fn rotated_field_still_gives_horizontal_ticks() {
        let mesh = shapes::plane(1.0, 8).expect("plane");
        let field = constant_field(&mesh, [1.0, 1.0, 0.0]);
        let p = param_all(&mesh, &field);
        assert!(p.report.valid);
        let tags_svg = atlas_svg(&mesh, &field, &[p]);
        let ticks = ticks(&parse(&tags_svg));
        assert_eq!(ticks.len(), mesh.face_count());
        assert!(ticks.iter().all(|t| sin_to_horizontal(*t) <= 1e-6));
    }

    #[test]
    fn plane_tilted_in_space_gives_horizontal_ticks() {
        // The per-triangle map is solved in the face plane, not in world xy.
        let flat = shapes::plane(1.0, 6).expect("plane");
        let rotation = DQuat::from_euler(glam::EulerRot::XYZ, 0.7, -0.4, 1.1);
        let positions = flat.positions().iter().map(|p| rotation * *p).collect();
        let mesh = TriMesh::new(positions, flat.triangles().to_vec()).expect("mesh");
        let d = rotation * DVec3::new(1.0, 2.0, 0.0);
        let field = constant_field(&mesh, d.to_array());
        let p = param_all(&mesh, &field);
        assert!(p.report.valid);
        let ticks = ticks(&parse(&atlas_svg(&mesh, &field, &[p])));
        assert_eq!(ticks.len(), mesh.face_count());
        assert!(ticks.iter().all(|t| sin_to_horizontal(*t) <= 1e-6));
    }

    #[test]
    fn ticks_follow_the_uv_map() {
        // Rotating the layout by 30 degrees (counter-clockwise, v up) turns every tick
        // by 30 degrees; in SVG coordinates (y down) that is -30 degrees.
        let mesh = shapes::plane(1.0, 8).expect("plane");
        let field = constant_field(&mesh, [1.0, 0.0, 0.0]);
        let mut p = param_all(&mesh, &field);
        let (s, c) = 30f64.to_radians().sin_cos();
        for q in &mut p.uv {
            *q = DVec2::new(c * q.x - s * q.y, s * q.x + c * q.y);
        }
        let ticks = ticks(&parse(&atlas_svg(&mesh, &field, &[p])));
        assert_eq!(ticks.len(), mesh.face_count());
        for [x1, y1, x2, y2] in ticks {
            // A line field: compare slopes, i.e. angles modulo 180 degrees.
            let angle = (y2 - y1).atan2(x2 - x1).to_degrees().rem_euclid(180.0);
            assert!((angle - 150.0).abs() < 0.5, "{angle}");
        }
    }

    #[test]
    fn mirrored_layout_draws_every_triangle_flipped() {
        let mesh = shapes::plane(1.0, 4).expect("plane");
        let field = constant_field(&mesh, [1.0, 0.0, 0.0]);
        let mut p = param_all(&mesh, &field);
        for q in &mut p.uv {
            q.x = -q.x;
        }
        let svg = atlas_svg(&mesh, &field, &[p]);
        let tags = parse(&svg);
        let flip = tags
            .iter()
            .find(|t| t.has_class("flip"))
            .and_then(|t| t.attr("d"))
            .expect("flip path");
        assert_eq!(flip.matches('Z').count(), mesh.face_count());
        // Mirroring u keeps the major direction on the u axis.
        assert!(ticks(&tags).iter().all(|t| sin_to_horizontal(*t) <= 1e-6));
    }

    #[test]
    fn several_segments_give_disjoint_tiles_holding_their_ticks() {
        let mesh = shapes::plane(1.0, 8).expect("plane");
        let field = constant_field(&mesh, [1.0, 1.0, 0.0]);
        // Five segments: the quadrants, the top-right one split once more.
        let mut groups = vec![Vec::new(); 5];
        for f in 0..mesh.face_count() as u32 {
            let c = mesh.face_positions(f).iter().sum::<DVec3>() / 3.0;
            let k = usize::from(c.x > 0.5) + 2 * usize::from(c.y > 0.5);
            let k = if k == 3 && c.x > 0.75 { 4 } else { k };
            groups[k].push(f);
        }
        let params: Vec<SegmentParam> = groups
            .iter()
            .map(|g| param_faces(&mesh, &field, g))
            .collect();
        let svg = atlas_svg(&mesh, &field, &params);
        let tags = parse(&svg);
        let mut tiles: Vec<[f64; 4]> = Vec::new();
        let mut tick_count = vec![0; params.len()];
        for t in &tags {
            if t.name == "rect" && t.has_class("tile") {
                let (x, y) = (t.num("x"), t.num("y"));
                tiles.push([x, y, x + t.num("width"), y + t.num("height")]);
            } else if t.name == "line" && t.has_class("tick") {
                let tile = tiles.last().expect("tick inside a tile");
                let [x1, y1, x2, y2] = [t.num("x1"), t.num("y1"), t.num("x2"), t.num("y2")];
                for (x, y) in [(x1, y1), (x2, y2)] {
                    assert!(x > tile[0] && x < tile[2] && y > tile[1] && y < tile[3]);
                }
                assert!(sin_to_horizontal([x1, y1, x2, y2]) <= 1e-6);
                tick_count[tiles.len() - 1] += 1;
            }
        }
        assert_eq!(tiles.len(), params.len());
        let expected: Vec<usize> = params.iter().map(|p| p.triangles.len()).collect();
        assert_eq!(tick_count, expected);
        for (i, a) in tiles.iter().enumerate() {
            for b in &tiles[..i] {
                let apart = a[2] <= b[0] || b[2] <= a[0] || a[3] <= b[1] || b[3] <= a[1];
                assert!(apart, "tiles {a:?} and {b:?} overlap");
            }
        }
        // The viewBox holds every tile.
        let view_box: Vec<f64> = tags[0]
            .attr("viewBox")
            .expect("viewBox")
            .split(' ')
            .map(|v| v.parse().expect("number"))
            .collect();
        assert!(
            tiles
                .iter()
                .all(|t| t[0] >= 0.0 && t[1] >= 0.0 && t[2] <= view_box[2] && t[3] <= view_box[3])
        );
    }

    #[test]
    fn large_segment_gets_every_kth_tick() {
        let mesh = shapes::plane(1.0, 40).expect("plane");
        let field = constant_field(&mesh, [1.0, 0.0, 0.0]);
        let p = param_all(&mesh, &field);
        let n = p.triangles.len();
        assert_eq!(n, 3200);
        let svg = atlas_svg(&mesh, &field, &[p]);
        let ticks = ticks(&parse(&svg));
        assert_eq!(ticks.len(), n.div_ceil(2));
        assert!(svg.contains("ticks 1/2"));
    }

    #[test]
    fn atlas_is_capped_at_max_segments() {
        let mesh = shapes::plane(1.0, 1).expect("plane");
        let field = constant_field(&mesh, [1.0, 0.0, 0.0]);
        let p = param_all(&mesh, &field);
        let params = vec![p; MAX_SEGMENTS + 3];
        let svg = atlas_svg(&mesh, &field, &params);
        let tags = parse(&svg);
        assert_eq!(
            tags.iter().filter(|t| t.has_class("tile")).count(),
            MAX_SEGMENTS
        );
        assert!(svg.contains(&format!("first {MAX_SEGMENTS} drawn")));
    }

    #[test]
    fn empty_atlas_is_valid_svg() {
        let mesh = shapes::plane(1.0, 1).expect("plane");
        let field = constant_field(&mesh, [1.0, 0.0, 0.0]);
        let svg = atlas_svg(&mesh, &field, &[]);
        let tags = parse(&svg);
        assert!(!tags.iter().any(|t| t.has_class("tile")));
    }

    #[test]
    fn writes_the_file_atomically() {
        let mesh = shapes::plane(1.0, 3).expect("plane");
        let field = constant_field(&mesh, [1.0, 0.0, 0.0]);
        let p = param_all(&mesh, &field);
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("atlas.svg");
        std::fs::write(&path, "old").expect("write");
        write_atlas_svg(&path, &mesh, &field, std::slice::from_ref(&p)).expect("write atlas");
        let text = std::fs::read_to_string(&path).expect("read");
        assert_eq!(text, atlas_svg(&mesh, &field, &[p]));
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .expect("dir")
            .map(|e| e.expect("entry").file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("atlas.svg")]);
        // A path in a missing folder fails without panicking.
        let missing = dir.path().join("no/such/atlas.svg");
        assert!(write_atlas_svg(&missing, &mesh, &field, &[]).is_err());
    }

    #[test]
    fn numbers_have_at_most_two_decimals() {
        let mut s = String::new();
        for x in [0.0, -0.001, 1.5, 2.0, 12.34567, -7.125, f64::NAN, 1234.999] {
            push_num(&mut s, x);
            s.push(' ');
        }
        assert_eq!(s, "0 0 1.5 2 12.35 -7.13 0 1235 ");
    }
}
