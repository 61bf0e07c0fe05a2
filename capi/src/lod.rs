//! Level of detail for hosts: a `StrataLod` pool of a sampler's progressive samples,
//! updated from a view-projection matrix and a viewport, reporting the ranks that
//! became visible or hidden since its last update, so a host streams only those to
//! its GPU.
//!
//! An update is the engine's `LodPool::update` (draws the ranks the view needs), then
//! each entry's visibility under the view (`LodPool::fades_into`: rank `k` is visible
//! when `k < N lod(p_k)`), compared with the last update's by a merge of the sorted
//! visible ranks. Cost: the pool's update plus O(entries log entries) for the
//! comparison; no allocation once the pool and the lists stop growing.

#![allow(unsafe_code)] // `#[unsafe(no_mangle)]` exports only; see `handle.rs` for the rest.

use std::sync::Mutex;

use glam::{DMat4, DVec4};
use strata_engine::sample::lod::{Budget, LodPool, PoolChange, ViewLod};
use strata_engine::sample::{Sample, Sampler};

use crate::handle::{
    Failure, Handle, Kind, Outcome, StrataStatus, borrow, check_struct_size, engine_error, guard,
    register, release, require_out, slice, slice_mut, write_out,
};
use crate::sample::{StrataSample, StrataSampler};

/// A level-of-detail pool (opaque). Any thread may call it; calls on one pool take
/// turns (it holds a lock). It keeps its own reference to the sampler's data, so the
/// sampler may be freed before it.
pub struct StrataLod {
    state: Mutex<State>,
}

impl Handle for StrataLod {
    const KIND: Kind = Kind::Lod;
}

struct State {
    sampler: Sampler,
    pool: LodPool,
    fades: Vec<f32>,
    /// Visible (rank, entry) of the last update, sorted by rank.
    visible: Vec<(u32, u32)>,
    /// This update's, being built.
    next: Vec<(u32, u32)>,
    shown: Vec<u32>,
    shown_entries: Vec<u32>,
    hidden: Vec<u32>,
    base: f64,
}

/// A camera, for `strata_lod_update`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrataView {
    /// `sizeof(StrataView)`.
    pub struct_size: u32,
    /// 1: faces turned away from the eye show nothing; 0: they show like the others.
    pub cull_back_faces: u32,
    /// Clip-from-world matrix (projection times view) of a perspective camera with a
    /// rigid view, column-major, clip z in [0, w] (Direct3D, Vulkan, Metal, wgpu). The
    /// eye and the focal length are taken from it.
    pub view_projection: [f64; 16],
    /// Viewport width in pixels (> 0).
    pub viewport_width: f64,
    /// Viewport height in pixels (> 0).
    pub viewport_height: f64,
    /// Screen area (pixels^2) that a unit of surface area covers where the density
    /// multiplier is 1 (> 0): larger shows fewer samples up close.
    pub reference: f64,
    /// Largest multiplier (> 0; infinity for none).
    pub max: f64,
    /// The base count: samples over the whole surface where the multiplier is 1.
    pub base_count: f64,
    /// A point budget: when > 0, the base count is chosen so that about this many
    /// samples show (`base_count` then applies only to a view of nothing).
    pub shown: u32,
}

/// What one `strata_lod_update` did.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrataLodFrame {
    /// The base count the frame thresholds with.
    pub base: f64,
    /// Entries (sites) the pool holds.
    pub entries: u64,
    /// Ranks visible now.
    pub visible: u64,
    /// Ranks that became visible since the last update (`strata_lod_changes`).
    pub became_visible: u64,
    /// Ranks that became hidden since the last update.
    pub became_hidden: u64,
    /// 1 when the pool's extension was rebuilt (its entry order changed), else 0.
    pub rebuilt: u32,
}

/// `strata_lod_changes`: the ranks that became visible.
pub const STRATA_LOD_SHOWN: u32 = 0;
/// `strata_lod_changes`: the ranks that became hidden.
pub const STRATA_LOD_HIDDEN: u32 = 1;

/// The engine's view from a host's camera.
fn view_lod(view: &StrataView) -> Outcome<ViewLod> {
    check_struct_size(view.struct_size, size_of::<StrataView>(), "StrataView")?;
    let invalid = |m: String| Err(Failure::new(StrataStatus::InvalidArgument, m));
    let positive = |x: f64| x > 0.0 && x.is_finite();
    if !(positive(view.viewport_width) && positive(view.viewport_height)) {
        return invalid(format!(
            "viewport {} x {} must be positive and finite",
            view.viewport_width, view.viewport_height
        ));
    }
    let m = DMat4::from_cols_array(&view.view_projection);
    if !m.is_finite() || m.determinant() == 0.0 {
        return invalid("view_projection must be finite and invertible".into());
    }
    // The eye maps to clip (0, 0, b, 0): it is the inverse's image of (0, 0, 1, 0).
    let eye = m.inverse() * DVec4::new(0.0, 0.0, 1.0, 0.0);
    if !(eye.w.abs() > 1e-300) {
        return invalid("view_projection is not a perspective projection".into());
    }
    // Rows y and w are `f` times and once the view's unit axes: their ratio is `f`.
    let (row_y, row_w) = (m.row(1).truncate(), m.row(3).truncate());
    let focal = 0.5 * view.viewport_height * row_y.length() / row_w.length();
    let lod = ViewLod {
        clip_from_world: m,
        eye: eye.truncate() / eye.w,
        focal_pixels: focal,
        reference: view.reference,
        max: view.max,
        cull_back_faces: view.cull_back_faces != 0,
    };
    lod.validate()
        .map_err(|e| engine_error(StrataStatus::Lod, "view", e))?;
    if !(view.base_count >= 0.0 && view.base_count.is_finite()) {
        return invalid(format!(
            "base_count is {}, it must be finite and >= 0",
            view.base_count
        ));
    }
    Ok(lod)
}

impl State {
    fn update(&mut self, view: &StrataView) -> Outcome<StrataLodFrame> {
        let lod = view_lod(view)?;
        let shown = (view.shown > 0).then_some(view.shown);
        let frame = self
            .pool
            .update(&self.sampler, &lod, Budget::new(view.base_count, shown))
            .map_err(|e| engine_error(StrataStatus::Lod, "update", e))?;
        self.base = frame.base;
        self.fades.resize(self.pool.len(), 0.0);
        self.pool
            .fades_into(&self.sampler, &lod, frame.base, &mut self.fades);
        self.next.clear();
        let ranks = self.pool.ranks();
        for (entry, (&fade, &rank)) in self.fades.iter().zip(ranks).enumerate() {
            if fade > 0.0 {
                self.next.push((rank, entry as u32));
            }
        }
        self.next.sort_unstable();
        self.diff();
        std::mem::swap(&mut self.visible, &mut self.next);
        Ok(StrataLodFrame {
            base: frame.base,
            entries: self.pool.len() as u64,
            visible: self.visible.len() as u64,
            became_visible: self.shown.len() as u64,
            became_hidden: self.hidden.len() as u64,
            rebuilt: u32::from(frame.change == PoolChange::Rebuilt),
        })
    }

    /// The ranks in `next` and not in `visible` (shown), and the other way (hidden).
    fn diff(&mut self) {
        self.shown.clear();
        self.shown_entries.clear();
        self.hidden.clear();
        let (mut i, mut j) = (0, 0);
        let (old, new) = (&self.visible, &self.next);
        while i < old.len() || j < new.len() {
            match (old.get(i), new.get(j)) {
                (Some(a), Some(b)) if a.0 == b.0 => {
                    i += 1;
                    j += 1;
                }
                (Some(a), Some(b)) if a.0 < b.0 => {
                    self.hidden.push(a.0);
                    i += 1;
                }
                (Some(a), None) => {
                    self.hidden.push(a.0);
                    i += 1;
                }
                (_, Some(b)) => {
                    self.shown.push(b.0);
                    self.shown_entries.push(b.1);
                    j += 1;
                }
                (None, None) => break,
            }
        }
    }
}

/// Makes a pool of `sampler`'s progressive sequence for `seed`, holding ranks
/// `0..prefix` and with room for `budget` more ranks drawn where views need them.
///
/// # Safety
/// `sampler` is a handle from this library; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_lod_create(
    sampler: *const StrataSampler,
    seed: u64,
    prefix: u32,
    budget: usize,
    out: *mut *mut StrataLod,
) -> StrataStatus {
    guard(|| {
        require_out(out, "out")?;
        let sampler = borrow(sampler, "sampler")?.sampler.clone();
        if prefix == 0 {
            return Err(Failure::new(
                StrataStatus::InvalidArgument,
                "prefix is 0: a pool holds at least rank 0",
            ));
        }
        let pool = LodPool::new(&sampler, seed, prefix, budget);
        let state = State {
            sampler,
            pool,
            fades: Vec::new(),
            visible: Vec::new(),
            next: Vec::new(),
            shown: Vec::new(),
            shown_entries: Vec::new(),
            hidden: Vec::new(),
            base: 0.0,
        };
        let handle = StrataLod {
            state: Mutex::new(state),
        };
        write_out(out, register(handle), "out")
    })
}

/// Brings the pool up to `view` and finds the ranks that became visible or hidden
/// since the last update (the first update reports every visible rank as shown).
///
/// # Safety
/// `lod` is a handle from this library; `view` points to a valid `StrataView`;
/// `frame` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_lod_update(
    lod: *const StrataLod,
    view: *const StrataView,
    frame: *mut StrataLodFrame,
) -> StrataStatus {
    guard(|| {
        let lod = borrow(lod, "lod")?;
        let view = &slice(view, 1, "view")?[0];
        let mut state = lod.state.lock().unwrap_or_else(|e| e.into_inner());
        let result = state.update(view)?;
        if !frame.is_null() {
            write_out(frame, result, "frame")?;
        }
        Ok(())
    })
}

/// Copies the ranks that became visible (`STRATA_LOD_SHOWN`) or hidden
/// (`STRATA_LOD_HIDDEN`) at the last update into `ranks` (ascending), `capacity` at
/// most; `count` receives how many there are (also when `ranks` is null, to size a
/// buffer). Too small a buffer is an error and writes nothing.
///
/// # Safety
/// `lod` is a handle from this library; `ranks` is null or holds `capacity` entries;
/// `count` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_lod_changes(
    lod: *const StrataLod,
    which: u32,
    ranks: *mut u32,
    capacity: usize,
    count: *mut usize,
) -> StrataStatus {
    guard(|| {
        require_out(count, "count")?;
        let lod = borrow(lod, "lod")?;
        let state = lod.state.lock().unwrap_or_else(|e| e.into_inner());
        let list = match which {
            STRATA_LOD_SHOWN => &state.shown,
            STRATA_LOD_HIDDEN => &state.hidden,
            other => {
                return Err(Failure::new(
                    StrataStatus::InvalidArgument,
                    format!("which is {other}, expected STRATA_LOD_SHOWN or STRATA_LOD_HIDDEN"),
                ));
            }
        };
        write_out(count, list.len(), "count")?;
        if ranks.is_null() {
            return Ok(());
        }
        if capacity < list.len() {
            return Err(Failure::new(
                StrataStatus::InvalidArgument,
                format!("capacity is {capacity}, {} ranks changed", list.len()),
            ));
        }
        slice_mut(ranks, list.len(), "ranks")?.copy_from_slice(list);
        Ok(())
    })
}

/// Writes the records of the ranks that became visible at the last update, in the
/// order `strata_lod_changes(STRATA_LOD_SHOWN)` lists them, into `records`
/// (`capacity` at least that count; spacings for the frame's base count).
///
/// # Safety
/// `lod` is a handle from this library; `records` holds `capacity` entries.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_lod_shown_records(
    lod: *const StrataLod,
    records: *mut StrataSample,
    capacity: usize,
) -> StrataStatus {
    guard(|| {
        let lod = borrow(lod, "lod")?;
        let state = lod.state.lock().unwrap_or_else(|e| e.into_inner());
        let n = state.shown_entries.len();
        if capacity < n {
            return Err(Failure::new(
                StrataStatus::InvalidArgument,
                format!("capacity is {capacity}, {n} ranks became visible"),
            ));
        }
        if records.is_null() && n > 0 {
            return Err(Failure::new(StrataStatus::NullPointer, "records is null"));
        }
        let out = slice_mut(records.cast::<Sample>(), n, "records")?;
        let count = state.base.round().max(1.0) as usize;
        let (sites, ranks) = (state.pool.sites(), state.pool.ranks());
        for (slot, &entry) in out.iter_mut().zip(&state.shown_entries) {
            let (site, rank) = (sites[entry as usize], ranks[entry as usize]);
            let bary = site.barycentric().map(f64::from);
            *slot = state
                .sampler
                .record(site.face, bary, site.segment, rank, count)
                .unwrap_or_default();
        }
        Ok(())
    })
}

/// Frees a pool (null: nothing); see `strata_mesh_free`.
///
/// # Safety
/// `lod` is null or a handle from this library, used by no other call now.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn strata_lod_free(lod: *mut StrataLod) -> StrataStatus {
    guard(|| release(lod, "lod"))
}
