//! Which sampler a pool was built from, so that a pool refuses to be extended with
//! another one (its entries are sites of that sampler's sequence, its bins cells of
//! that sampler's curves: another sampler's ranks would land in the wrong places).
//!
//! Input: a [`Sampler`]. Output: a key that holds the sampler's shared parts (the mesh,
//! the field and every segment's curve, by reference count) and its chain order, and
//! says whether another sampler has the same ones. Cost: O(segments) pointer
//! comparisons per check, allocating nothing (it runs every frame), nothing per
//! sample.
//!
//! A [`Sampler`]'s clone shares its mesh, field and curves, so it is the same sampler
//! here; a sampler rebuilt from new cells, a new field or a new mesh is another one,
//! even with equal contents. The key holds the shared parts alive, so no later
//! allocation can take their addresses.

use std::sync::Arc;

use crate::curve::SegmentCurve;
use crate::field::TensorField;
use crate::mesh::TriMesh;
use crate::sample::Sampler;

/// The identity of a [`Sampler`]: see the module docs.
#[derive(Clone, Debug)]
pub(super) struct SamplerKey {
    mesh: Arc<TriMesh>,
    field: Arc<TensorField>,
    /// Per segment: its id, its curve and its number of domain faces.
    segments: Vec<(u32, Arc<SegmentCurve>, usize)>,
    /// The segments in chain order, and the length of each chain.
    chain_order: Vec<u32>,
    chain_lengths: Vec<u32>,
}

impl SamplerKey {
    /// The key of `sampler`.
    pub(super) fn new(sampler: &Sampler) -> Self {
        let chains = sampler.chains();
        Self {
            mesh: sampler.mesh().clone(),
            field: sampler.field().clone(),
            segments: sampler
                .segments()
                .iter()
                .map(|s| (s.segment, s.curve.clone(), s.faces.len()))
                .collect(),
            chain_order: chains.iter().flat_map(|c| c.iter().copied()).collect(),
            chain_lengths: chains.iter().map(|c| c.len() as u32).collect(),
        }
    }

    /// Whether `sampler` is the sampler of this key (or a clone of it).
    pub(super) fn matches(&self, sampler: &Sampler) -> bool {
        let segments = sampler.segments();
        Arc::ptr_eq(&self.mesh, sampler.mesh())
            && Arc::ptr_eq(&self.field, sampler.field())
            && segments.len() == self.segments.len()
            && segments
                .iter()
                .zip(&self.segments)
                .all(|(s, (id, curve, faces))| {
                    s.segment == *id && Arc::ptr_eq(&s.curve, curve) && s.faces.len() == *faces
                })
            && sampler.chains_iter().len() == self.chain_lengths.len()
            && sampler
                .chains_iter()
                .zip(&self.chain_lengths)
                .all(|(c, &n)| c.len() == n as usize)
            && sampler
                .chains_iter()
                .flat_map(|c| c.iter())
                .eq(self.chain_order.iter())
    }
}
