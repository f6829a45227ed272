//! The boundary of the walk (traversal.py's `_Boundary`): the directed edges of the faces so far
//! whose opposite edge no face has yet, and the gates to pop.

use super::hash::FastMap;
use super::{edge, ends};

/// No entry below (the bottom of a stack).
const BOTTOM: usize = usize::MAX;

/// One entry of a vertex's stack of edges: an edge's key and the entry below it.
#[derive(Clone, Copy)]
struct Entry {
    key: u64,
    below: usize,
}

/// `open[x -> y]` counts how often x -> y is open (more than once only where faces overlap).
/// Each vertex has two stacks, of the edges into it and out of it, in the order they opened:
/// an entry stays when its edge closes and is popped for good once found on top while closed,
/// so that reading the newest open edge is O(1) amortized (as in the reference). The stacks
/// are linked lists in two arenas, which grow with the corners, never with a file's claims.
pub struct Boundary {
    pub open: FastMap<u64, u64>,
    pub gates: Vec<u64>,
    into_top: Vec<usize>,
    out_of_top: Vec<usize>,
    into_entries: Vec<Entry>,
    out_of_entries: Vec<Entry>,
}

impl Boundary {
    /// A boundary of `vertices` vertex ids (more are added by [`Boundary::add_vertex`]).
    pub fn new(vertices: usize) -> Self {
        Boundary {
            open: FastMap::default(),
            gates: Vec::new(),
            into_top: vec![BOTTOM; vertices],
            out_of_top: vec![BOTTOM; vertices],
            into_entries: Vec::new(),
            out_of_entries: Vec::new(),
        }
    }

    /// One more vertex id, the next one.
    pub fn add_vertex(&mut self) {
        self.into_top.push(BOTTOM);
        self.out_of_top.push(BOTTOM);
    }

    /// Whether the edge `key` is open.
    #[inline]
    pub fn is_open(&self, key: u64) -> bool {
        self.open.contains_key(&key)
    }

    /// The edge x -> y of a face joins the boundary: it closes an open y -> x, or opens (once
    /// more). Its key.
    pub fn join(&mut self, x: u32, y: u32) -> u64 {
        let key = edge(x, y);
        let opposite = edge(y, x);
        if let Some(count) = self.open.get_mut(&opposite) {
            if *count == 1 {
                // y -> x closes: its entries in into(x) and out_of(y) go stale
                self.open.remove(&opposite);
            } else {
                *count -= 1;
            }
        } else if let Some(count) = self.open.get_mut(&key) {
            *count += 1;
        } else {
            // x -> y opens: the newest entry of both ends
            self.open.insert(key, 1);
            push(&mut self.into_top, &mut self.into_entries, y, key);
            push(&mut self.out_of_top, &mut self.out_of_entries, x, key);
        }
        key
    }

    /// Adds the face `cycle` (in walk order); its edges from `first_gate` on become gates.
    pub fn attach(&mut self, cycle: &[u32], first_gate: usize) {
        let n = cycle.len();
        for j in 0..n {
            let key = self.join(cycle[j], cycle[(j + 1) % n]);
            if j >= first_gate {
                self.gates.push(key);
            }
        }
    }

    /// The u of the newest open u -> v (PREV), closed entries on top popped for good.
    pub fn newest_into(&mut self, v: u32) -> Option<u32> {
        newest(&mut self.into_top, &self.into_entries, &self.open, v).map(|key| ends(key).0)
    }

    /// The w of the newest open v -> w (NEXT), closed entries on top popped for good.
    pub fn newest_out_of(&mut self, v: u32) -> Option<u32> {
        newest(&mut self.out_of_top, &self.out_of_entries, &self.open, v).map(|key| ends(key).1)
    }
}

fn push(tops: &mut [usize], entries: &mut Vec<Entry>, vertex: u32, key: u64) {
    // every vertex id on an edge was added before (the walk's ids are checked)
    if let Some(top) = tops.get_mut(vertex as usize) {
        entries.push(Entry { key, below: *top });
        *top = entries.len() - 1;
    }
}

fn newest(
    tops: &mut [usize],
    entries: &[Entry],
    open: &FastMap<u64, u64>,
    vertex: u32,
) -> Option<u64> {
    let top = tops.get_mut(vertex as usize)?;
    while let Some(entry) = entries.get(*top) {
        if open.contains_key(&entry.key) {
            return Some(entry.key);
        }
        *top = entry.below;
    }
    None
}
