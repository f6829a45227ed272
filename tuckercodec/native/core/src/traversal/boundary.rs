//! The boundary of the walk (traversal.py's `_Boundary`): the directed edges of the faces so far
//! whose opposite edge no face has yet, and the gates to pop.

use std::collections::hash_map::Entry as MapEntry;

use super::edge;
use super::hash::FastMap;

/// No entry below (the bottom of a stack).
const BOTTOM: u32 = u32::MAX;

/// One entry of a vertex's stack of edges: the edge's other end, and the entry below it.
#[derive(Clone, Copy)]
struct Entry {
    other: u32,
    below: u32,
}

/// `open[x -> y]` counts how often x -> y is open (more than once only where faces overlap).
/// Each vertex has two stacks, of the edges into it and out of it, in the order they opened:
/// an entry stays when its edge closes and is popped for good once found on top while closed,
/// so that reading the newest open edge is O(1) amortized (as in the reference). The stacks
/// are linked lists in two arenas, which grow with the corners, never with a file's claims.
///
/// Entries are numbered by u32: the walk opens fewer than 2**32 - 1 edges (the callers bound
/// the streams' lengths, [`MAX_VALUES`](super::MAX_VALUES)); one past it is not pushed.
pub struct Boundary {
    pub open: FastMap<u64, u32>,
    pub gates: Vec<u64>,
    into_top: Vec<u32>,
    out_of_top: Vec<u32>,
    into_entries: Vec<Entry>,
    out_of_entries: Vec<Entry>,
}

impl Boundary {
    /// A boundary of `vertices` vertex ids (more are added by [`Boundary::add_vertex`]), with
    /// room for `open_edges` open edges (a hint: growing the table as it fills costs more).
    pub fn new(vertices: usize, open_edges: usize) -> Self {
        let mut open = FastMap::default();
        open.reserve(open_edges);
        Boundary {
            open,
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
        // one probe for each edge looked at: entry() finds and removes alike
        if let MapEntry::Occupied(mut opposite) = self.open.entry(edge(y, x)) {
            if *opposite.get() == 1 {
                // y -> x closes: its entries in into(x) and out_of(y) go stale
                opposite.remove();
            } else {
                *opposite.get_mut() -= 1;
            }
            return key;
        }
        match self.open.entry(key) {
            MapEntry::Occupied(mut open) => *open.get_mut() += 1,
            MapEntry::Vacant(vacant) => {
                // x -> y opens: the newest entry of both ends
                vacant.insert(1);
                push(&mut self.into_top, &mut self.into_entries, y, x);
                push(&mut self.out_of_top, &mut self.out_of_entries, x, y);
            }
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
        let open = &self.open;
        newest(&mut self.into_top, &self.into_entries, v, |u| {
            open.contains_key(&edge(u, v))
        })
    }

    /// The w of the newest open v -> w (NEXT), closed entries on top popped for good.
    pub fn newest_out_of(&mut self, v: u32) -> Option<u32> {
        let open = &self.open;
        newest(&mut self.out_of_top, &self.out_of_entries, v, |w| {
            open.contains_key(&edge(v, w))
        })
    }
}

/// Pushes `other` on the stack of `vertex` (a vertex id the walk added).
fn push(tops: &mut [u32], entries: &mut Vec<Entry>, vertex: u32, other: u32) {
    let Some(number) = u32::try_from(entries.len()).ok().filter(|&n| n != BOTTOM) else {
        return;
    };
    if let Some(top) = tops.get_mut(vertex as usize) {
        entries.push(Entry { other, below: *top });
        *top = number;
    }
}

/// The other end of the newest open edge on the stack of `vertex`.
fn newest(
    tops: &mut [u32],
    entries: &[Entry],
    vertex: u32,
    is_open: impl Fn(u32) -> bool,
) -> Option<u32> {
    let top = tops.get_mut(vertex as usize)?;
    while let Some(entry) = entries.get(*top as usize) {
        if is_open(entry.other) {
            return Some(entry.other);
        }
        *top = entry.below;
    }
    None
}
