//! §6.8 with `coder` 1 (format 1.6): a NEW tip's vertex as its signed rank among the vertices
//! not seen yet (`tuckercodec/format/unseen.py` is the reference; read its docstring first).
//!
//! The rank of w is u(w) − u(last), u(x) the unseen vertices below x (0 while last is −1), so
//! the running sum of the ranks is u of each new vertex: [`vertices`] finds the unseen vertex
//! with t unseen below it, [`ranks`] counts the placed vertices below w, both by a Fenwick tree
//! over the placed vertices in O(log K).

use super::hash::FastMap;
use super::RULE;
use crate::error::Broken;

/// The largest vertex count taken (so that every count and rank fits an i64).
pub const MAX_K: u64 = 1 << 62;

/// The counts of the placed vertices among `0..k` (a Fenwick tree, 1-based nodes). Its nodes
/// are a table where `k` is within a few times the vertices the file places (as the walk's
/// `VertexIds`), else a hash map filled as vertices are placed: `k` is the header's claim and
/// must not size an allocation.
struct Placed {
    top: u64,
    nodes: Nodes,
}

enum Nodes {
    Table(Vec<u32>),
    Map(FastMap<u64, u32>),
}

impl Placed {
    fn new(k: u64, placed_at_most: usize) -> Self {
        // a power of two >= k, for the descent
        let top = k.max(1).next_power_of_two();
        let bound = 4 * placed_at_most as u128 + 1024;
        let nodes = match usize::try_from(top) {
            Ok(size) if (size as u128) <= bound => Nodes::Table(vec![0; size + 1]),
            _ => Nodes::Map(FastMap::default()),
        };
        Placed { top, nodes }
    }

    #[inline]
    fn node(&self, i: u64) -> u64 {
        match &self.nodes {
            Nodes::Table(table) => u64::from(table[i as usize]),
            Nodes::Map(map) => u64::from(map.get(&i).copied().unwrap_or(0)),
        }
    }

    /// Marks `v` (unplaced, below k) as placed.
    fn place(&mut self, v: u64) {
        let mut i = v + 1;
        while i <= self.top {
            match &mut self.nodes {
                Nodes::Table(table) => table[i as usize] += 1,
                Nodes::Map(map) => *map.entry(i).or_insert(0) += 1,
            }
            i += i & i.wrapping_neg();
        }
    }

    /// How many placed vertices are below `x`.
    fn below(&self, mut x: u64) -> u64 {
        let mut total = 0;
        while x > 0 {
            total += self.node(x);
            x &= x - 1;
        }
        total
    }

    /// The unplaced vertex with exactly `t` unplaced vertices below it (t below the count of
    /// unplaced vertices): the binary descent of a Fenwick tree.
    fn unplaced(&self, mut t: u64) -> u64 {
        let (mut position, mut step) = (0, self.top);
        while step > 0 {
            let node = position + step;
            let free = step - self.node(node); // unplaced vertices in position..node-1
            if free <= t {
                position = node;
                t -= free;
            }
            step >>= 1;
        }
        position
    }
}

/// The rank of each NEW vertex among the unseen ones, for `vertices` in `0..k` in the walk's
/// order (what the encoder's walk places: distinct, else the ranks mean nothing, but nothing
/// fails); None for a vertex outside `0..k`. `k` is at most 2**62.
pub fn ranks(vertices: &[i64], k: u64) -> Option<Vec<i64>> {
    if k > MAX_K {
        return None;
    }
    let mut placed = Placed::new(k, vertices.len());
    let mut out = Vec::with_capacity(vertices.len());
    let mut before: i64 = 0;
    for &w in vertices {
        let w = u64::try_from(w).ok().filter(|&w| w < k)?;
        // signed, as the reference's: vertices placed twice may count more than w below it
        let t = w as i64 - placed.below(w) as i64;
        out.push(t - before);
        placed.place(w);
        before = t;
    }
    Some(out)
}

/// The NEW vertices, in turn, that `ranks` name among `0..k`, or a [`Broken`] of R39-traversal
/// at the first rank that names no unseen vertex (the detail the reference gives). Memory grows
/// with the ranks, never with `k` beyond a few times their count. `k` above 2**62 counts as
/// 2**62: 2**30 ranks of magnitude below 2**31 (what a FACE section can hold) never reach it.
pub fn vertices(ranks: &[i64], k: u64) -> Result<Vec<i64>, Broken> {
    let k = k.min(MAX_K);
    let mut placed = Placed::new(k, ranks.len());
    let mut out = Vec::with_capacity(ranks.len());
    let mut t: i128 = 0;
    for (count, &r) in ranks.iter().enumerate() {
        t += i128::from(r); // |t| < 2**94: no overflow
        let unseen = i128::from(k) - count as i128;
        if t < 0 || t >= unseen {
            return Err(Broken::new(
                RULE,
                format!("new vertex rank {r} names no unseen vertex"),
            ));
        }
        let w = placed.unplaced(t as u64);
        placed.place(w);
        out.push(w as i64);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::{ranks, vertices, Placed};

    /// The ranks by their definition: u(w) − u(last) with u counted directly.
    fn by_definition(order: &[i64]) -> Vec<i64> {
        let mut out = Vec::new();
        let mut before = 0;
        for (i, &w) in order.iter().enumerate() {
            let u = w - order[..i].iter().filter(|&&v| v < w).count() as i64;
            out.push(u - before);
            before = u;
        }
        out
    }

    #[test]
    fn ranks_and_vertices_invert_each_other() {
        let order = [5_i64, 6, 2, 9, 0, 7, 1, 3];
        for k in [10_u64, 11, 16, 1 << 40, 1 << 62] {
            let coded = ranks(&order, k).unwrap();
            assert_eq!(coded, by_definition(&order));
            assert_eq!(vertices(&coded, k).unwrap(), order);
        }
        assert_eq!(ranks(&order, 10).unwrap(), [5, 0, -3, 4, -6, 3, -3, 0]);
    }

    #[test]
    fn a_rank_beyond_the_unseen_vertices_is_refused() {
        // 3 vertices: after 1 and 2 only 0 is left, below
        assert_eq!(vertices(&[1, 0, -1], 3).unwrap(), [1, 2, 0]);
        for bad in [[1_i64, 0, 0], [1, 0, -2], [3, 0, 0], [-1, 0, 0]] {
            let error = vertices(&bad, 3).unwrap_err();
            assert_eq!(error.rule, "R39-traversal");
        }
        assert!(vertices(&[i64::MAX, i64::MAX], u64::MAX).is_err());
        assert!(ranks(&[0], u64::MAX).is_none());
        assert!(ranks(&[3], 3).is_none());
        // not a walk's (a vertex twice), yet no overflow: the reference's signed values
        assert_eq!(ranks(&[0, 0, 1], 3).unwrap(), [0, 0, -1]);
    }

    #[test]
    fn the_sparse_and_dense_trees_agree() {
        let mut dense = Placed::new(64, 64);
        let mut sparse = Placed::new(64, 0);
        sparse.nodes = super::Nodes::Map(Default::default());
        for v in [3_u64, 40, 17, 0, 63] {
            dense.place(v);
            sparse.place(v);
        }
        for t in 0..59 {
            assert_eq!(dense.unplaced(t), sparse.unplaced(t));
        }
        for x in 0..=64 {
            assert_eq!(dense.below(x), sparse.below(x));
        }
    }
}
