//! The two order-dependent steps that turn a surface's parameterized pieces into a
//! sampler's input: the total measure that budgets the cells ([`total_measure`]) and
//! the segments in sampler order, numbered ([`order_segments`]).
//!
//! Both order pieces by their lowest mesh face
//! ([`lowest_face`](super::lowest_face)), the order of a whole build. A caller that
//! keeps pieces elsewhere, in any order (the ECS layer keeps them per segment entity),
//! gets the same total and the same sampler as
//! [`Preprocessed::build`](super::Preprocessed::build) by calling these, which the
//! whole build calls too.
//!
//! Input: one `(lowest face, ...)` tuple per piece. Output: an `f64`, or the
//! [`SegmentSampling`]s for [`Sampler::new`](crate::sample::Sampler::new). Cost:
//! O(n log n) in the number of pieces.

use std::sync::Arc;

use crate::curve::SegmentCurve;
use crate::sample::SegmentSampling;

/// The total measure of a surface's pieces, given as `(lowest face, measure)` pairs
/// in any order: the measures summed in lowest-face order.
///
/// Floating-point addition is not associative, so the order fixes the bits of the
/// sum; summing in lowest-face order makes it bit-identical to the total a whole
/// build ([`Preprocessed::build`](super::Preprocessed::build)) uses, and hence the
/// cell budgets of [`segment_cells`](super::segment_cells) too. Lowest faces are
/// distinct for disjoint non-empty pieces; ties (empty pieces) are broken by the
/// measure, so the result never depends on the input order. Cost: O(n log n).
pub fn total_measure(pieces: impl IntoIterator<Item = (u32, f64)>) -> f64 {
    let mut pieces: Vec<(u32, f64)> = pieces.into_iter().collect();
    pieces.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pieces.iter().map(|p| p.1).sum()
}

/// A surface's pieces, given as `(lowest face, faces, cells)` in any order, as the
/// segments of a [`Sampler`](crate::sample::Sampler): sorted by lowest face and
/// numbered `0..n` in that order.
///
/// The order is the segment order of a whole build
/// ([`Preprocessed::build`](super::Preprocessed::build)): it fixes the segment ids
/// written into samples and the chains the sampler links, so a sampler assembled
/// from the same pieces in another order samples bit for bit the same. Ties (empty
/// pieces only) are broken by the face lists. Cost: O(n log n), moving the inputs.
pub fn order_segments(
    pieces: impl IntoIterator<Item = (u32, Vec<u32>, Arc<SegmentCurve>)>,
) -> Vec<SegmentSampling> {
    let mut pieces: Vec<(u32, Vec<u32>, Arc<SegmentCurve>)> = pieces.into_iter().collect();
    pieces.sort_by(|a, b| a.0.cmp(&b.0).then_with(|| a.1.cmp(&b.1)));
    pieces
        .into_iter()
        .enumerate()
        .map(|(id, (_, faces, curve))| SegmentSampling {
            segment: id as u32,
            faces,
            curve,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::CellInput;
    use crate::fixtures::torus_case;
    use crate::surface::{Preprocessed, SurfaceOptions, lowest_face, segment_cells};

    /// A fixed permutation of `0..n` (Fisher-Yates with a xorshift), far from sorted.
    fn shuffled(n: usize) -> Vec<usize> {
        let mut order: Vec<usize> = (0..n).collect();
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for i in (1..n).rev() {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            order.swap(i, (state % (i as u64 + 1)) as usize);
        }
        order
    }

    #[test]
    fn total_and_order_reproduce_a_whole_build_bit_for_bit_in_any_input_order() {
        let (mesh, field) = torus_case();
        let options = SurfaceOptions::default();
        let pre = Preprocessed::build(mesh.clone(), field.clone(), &options).expect("build");
        let n = pre.params.len();
        assert!(
            n > 2,
            "the torus case should give several segments, got {n}"
        );
        let built = pre.sampler.segments();
        let inputs: Vec<CellInput> = pre
            .params
            .iter()
            .map(|p| CellInput::new(&mesh, &field, p))
            .collect();
        let order = shuffled(n);
        assert_ne!(order, (0..n).collect::<Vec<_>>());

        // The total: the build's params are in lowest-face order, so its sum is the
        // plain sum in that order; any input order gives the same bits.
        let in_order: f64 = inputs.iter().map(|c| c.measure).sum();
        let keyed = |i: usize| (lowest_face(&pre.params[i]), inputs[i].measure);
        let total = total_measure((0..n).map(keyed));
        assert_eq!(total.to_bits(), in_order.to_bits());
        assert_eq!(
            total_measure(order.iter().map(|&i| keyed(i))).to_bits(),
            total.to_bits()
        );
        assert_eq!(
            total_measure((0..n).rev().map(keyed)).to_bits(),
            total.to_bits()
        );
        // It is the total the build budgeted with: each segment's cells come out the
        // same from it.
        for ((p, input), s) in pre.params.iter().zip(&inputs).zip(built) {
            let curve = segment_cells(p, input, total, &options.curve).expect("cells");
            assert_eq!(curve.cell_count(), s.curve.cell_count());
            assert_eq!(curve.measure().to_bits(), s.curve.measure().to_bits());
        }

        // The order: the build's pieces, shuffled, come back as its segments.
        let pieces = order.iter().map(|&i| {
            let p = &pre.params[i];
            (lowest_face(p), p.faces.clone(), Arc::clone(&built[i].curve))
        });
        let segments = order_segments(pieces);
        assert_eq!(segments.len(), built.len());
        for (i, (a, b)) in segments.iter().zip(built).enumerate() {
            assert_eq!(a.segment, i as u32);
            assert_eq!(a.segment, b.segment);
            assert_eq!(a.faces, b.faces);
            assert!(Arc::ptr_eq(&a.curve, &b.curve));
        }
    }

    #[test]
    fn ties_and_empty_input_do_not_depend_on_the_input_order() {
        assert_eq!(total_measure([]), 0.0);
        assert!(order_segments([]).is_empty());
        let a = [(3, 0.1), (1, 0.2), (1, 1e-17), (2, 0.3)];
        let mut b = a;
        b.reverse();
        assert_eq!(total_measure(a).to_bits(), total_measure(b).to_bits());
    }
}
