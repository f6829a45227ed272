//! The decoder's walk (traversal.py's `_walk`, and `_walk_triangles` for tables of triangles,
//! which gives the same faces and errors): the faces rebuilt from the four streams.

use super::boundary::Boundary;
use super::hash::FastMap;
use super::{
    ends, first_smallest, GATE_NONE, MAX_VALUES, ROTATE_FROM_SMALLEST, RULE, STREAM_NAMES, TIP_FAR,
    TIP_NEW, TIP_NEXT, TIP_PREV,
};
use crate::error::Broken;

/// The four integer streams of a faces-traverse payload (§6.8), as decompressed: any values.
#[derive(Clone, Copy, Debug)]
pub struct Streams<'a> {
    pub ops: &'a [i64],
    /// Empty for a table of triangles, else one `degree - 3` per face.
    pub degrees: &'a [i64],
    /// The NEW tips' residuals.
    pub vertices: &'a [i64],
    /// The FAR tips' residuals.
    pub references: &'a [i64],
}

/// The `(count, width)` face table, row-major, padded with -1, that the walk decodes from
/// `streams` for `k` vertices, each face turned to its stored rotation for `corner_order` (1:
/// counted from the smallest corner; any other value: from the walk's first corner).
///
/// Same faces as the Python reference, and for a walk that breaks, a [`Broken`] of rule
/// R39-traversal whose detail is the text the reference puts after "the traversal breaks: ",
/// for the same first problem (including "a stream ends early" where the reference reads past
/// a stream's end). Never panics, whatever the values. Memory grows with the values read (the
/// walk stops at a stream's end), never with `k` or `count`, except that each decoded face
/// takes `width` entries: the caller bounds `width` (the reader checks the shape against the
/// limits first). Streams of more than [`MAX_VALUES`] values in all are refused (the limits on
/// a section keep a file far below; the Python caller runs its reference beyond).
pub fn decode(
    streams: &Streams<'_>,
    count: usize,
    width: usize,
    k: i64,
    corner_order: i64,
) -> Result<Vec<i64>, Broken> {
    let values = [
        streams.ops,
        streams.degrees,
        streams.vertices,
        streams.references,
    ];
    if values
        .iter()
        .map(|stream| stream.len() as u128)
        .sum::<u128>()
        > MAX_VALUES as u128
    {
        return Err(broken("streams of more than 2**30 values"));
    }
    // at most one face per op, and a face opens about two edges (a hint for the tables)
    let faces_at_most = count.min(streams.ops.len());
    let mut walk = Walk {
        ops: Reader::new(streams.ops),
        degrees: Reader::new(streams.degrees),
        vertices: Reader::new(streams.vertices),
        references: Reader::new(streams.references),
        polygons: !streams.degrees.is_empty(),
        k,
        placed: Vec::with_capacity(streams.vertices.len()),
        id_of: VertexIds::new(k, streams.vertices.len()),
        last_new: -1,
        boundary: Boundary::new(0, 2 * faces_at_most),
        width,
        smallest: corner_order == ROTATE_FROM_SMALLEST,
    };
    let mut table = Vec::new();
    // a hint only, so a failure to reserve is no error here
    let _ = table.try_reserve(faces_at_most.saturating_mul(width));
    let mut cycle = Vec::new();
    let mut values = Vec::new();
    let mut faces = 0;
    while faces < count {
        if walk.face(&mut cycle, &mut values, &mut table)? {
            faces += 1;
        }
    }
    walk.check_spent()?;
    Ok(table)
}

fn broken(detail: impl Into<String>) -> Broken {
    Broken::new(RULE, detail)
}

/// A stream read in turn; reading past its end is "a stream ends early".
struct Reader<'a> {
    values: &'a [i64],
    at: usize,
}

impl<'a> Reader<'a> {
    fn new(values: &'a [i64]) -> Self {
        Reader { values, at: 0 }
    }

    #[inline]
    fn next(&mut self) -> Result<i64, Broken> {
        let value = self.values.get(self.at).copied();
        self.at += 1;
        value.ok_or_else(|| broken("a stream ends early"))
    }

    fn has_left(&self) -> bool {
        self.at < self.values.len()
    }
}

/// The walk's state. Vertices are named inside by ids in the order they were placed (NEW),
/// so that the tables by vertex grow with the vertices met, never with the header's `k`.
struct Walk<'a> {
    ops: Reader<'a>,
    degrees: Reader<'a>,
    vertices: Reader<'a>,
    references: Reader<'a>,
    polygons: bool,
    k: i64,
    /// The vertex of each id.
    placed: Vec<i64>,
    id_of: VertexIds,
    last_new: i64,
    boundary: Boundary,
    width: usize,
    smallest: bool,
}

impl Walk<'_> {
    /// One step: a gate (true when a face crossed it) or a seed (true); the face's stored row
    /// is added to `table`.
    fn face(
        &mut self,
        cycle: &mut Vec<u32>,
        values: &mut Vec<i64>,
        table: &mut Vec<i64>,
    ) -> Result<bool, Broken> {
        cycle.clear();
        let (mut tip_op, rotation, first_gate);
        if let Some(gate) = self.boundary.gates.pop() {
            // a gate closed since it was pushed reads no op; GATE_NONE: no face across it
            if !self.boundary.is_open(gate) {
                return Ok(false);
            }
            let op = self.ops.next()?;
            if op == GATE_NONE {
                return Ok(false);
            }
            let top = 8 * self.width as u128;
            if op < 1 || op as u128 > top {
                return Err(broken(format!("gate operation {op} is outside 0..{top}")));
            }
            let code = op - 1; // rotation * 8 + 4 * flipped + first tip
            let (a, b) = ends(gate);
            cycle.extend(if code & 4 != 0 { [a, b] } else { [b, a] });
            tip_op = code & 3;
            rotation = code >> 3;
            first_gate = 1;
        } else {
            // a seed: every corner is a tip
            tip_op = self.ops.next()?;
            rotation = 0;
            first_gate = 0;
        }
        let n = if self.polygons {
            3 + i128::from(self.degrees.next()?)
        } else {
            3
        };
        if n < 3 || n > self.width as i128 {
            let width = self.width;
            return Err(broken(format!(
                "a face of {n} corners in a table of width {width}"
            )));
        }
        let n = n as usize;
        values.clear();
        values.extend(cycle.iter().map(|&id| self.placed[id as usize]));
        let mut previous = values.last().copied().unwrap_or(0);
        while cycle.len() < n {
            let id = self.tip(tip_op, cycle, previous)?;
            previous = self.placed[id as usize];
            cycle.push(id);
            values.push(previous);
            if cycle.len() < n {
                tip_op = self.ops.next()?;
            }
        }
        if rotation >= n as i64 {
            return Err(broken(format!(
                "rotation {rotation} of a face of {n} corners"
            )));
        }
        let mut offset = rotation as usize;
        if self.smallest && first_gate == 1 {
            offset += n - first_smallest(values);
        }
        // stored[(offset + j) % n] = cycle[j]
        let start = table.len();
        if table.try_reserve(self.width).is_err() {
            return Err(broken(format!(
                "a table of width {} does not fit",
                self.width
            )));
        }
        table.resize(start + self.width, -1);
        let row = &mut table[start..start + n];
        for (j, value) in values.iter().enumerate() {
            row[(offset + j) % n] = *value;
        }
        self.boundary.attach(cycle, first_gate);
        Ok(true)
    }

    /// The vertex id a tip names: NEW, FAR, PREV (the newest open u -> previous corner) or NEXT
    /// (the newest open first corner -> w).
    fn tip(&mut self, tip_op: i64, cycle: &[u32], previous: i64) -> Result<u32, Broken> {
        match tip_op {
            TIP_NEW => {
                let w = i128::from(self.last_new) + 1 + i128::from(self.vertices.next()?);
                let known = i64::try_from(w)
                    .ok()
                    .filter(|&v| v >= 0 && v < self.k && self.id_of.get(v).is_none());
                let Some(vertex) = known else {
                    let last = i128::from(self.k) - 1;
                    return Err(broken(format!(
                        "new vertex {w} is outside 0..{last} or placed"
                    )));
                };
                // fewer ids than values in the streams, checked below 2**30
                let id = self.placed.len() as u32;
                self.placed.push(vertex);
                self.id_of.insert(vertex, id);
                self.boundary.add_vertex();
                self.last_new = vertex;
                Ok(id)
            }
            TIP_FAR => {
                let w = i128::from(previous) + i128::from(self.references.next()?);
                let id = i64::try_from(w).ok().and_then(|v| self.id_of.get(v));
                id.ok_or_else(|| broken(format!("referenced vertex {w} is not one seen before")))
            }
            TIP_PREV | TIP_NEXT if !cycle.is_empty() => {
                let found = if tip_op == TIP_PREV {
                    self.boundary.newest_into(cycle[cycle.len() - 1])
                } else {
                    self.boundary.newest_out_of(cycle[0])
                };
                found.ok_or_else(|| broken(format!("tip operation {tip_op} names no vertex here")))
            }
            _ => Err(broken(format!(
                "tip operation {tip_op} names no vertex here"
            ))),
        }
    }

    /// Every stream read to its end, checked in the streams' order.
    fn check_spent(&self) -> Result<(), Broken> {
        let readers = [&self.ops, &self.degrees, &self.vertices, &self.references];
        for (name, reader) in STREAM_NAMES.iter().zip(readers) {
            if reader.has_left() {
                return Err(broken(format!(
                    "stream {name} has values left, or ends early"
                )));
            }
        }
        Ok(())
    }
}

/// The id of each placed vertex: a table by vertex where `k` is within a few times the number
/// of values of the vertices stream (its memory bounded by the values the file holds, as for
/// the rest of the walk), else a hash map (a header claiming many more vertices than placed).
enum VertexIds {
    Table(Vec<u32>),
    Map(FastMap<i64, u32>),
}

/// No id in the table.
const NO_ID: u32 = u32::MAX;

impl VertexIds {
    fn new(k: i64, placed_at_most: usize) -> Self {
        let bound = 4 * placed_at_most as u128 + 1024;
        match usize::try_from(k) {
            Ok(size) if (size as u128) <= bound => VertexIds::Table(vec![NO_ID; size]),
            _ => VertexIds::Map(FastMap::default()),
        }
    }

    /// The id of vertex `v` (any value), if it was placed.
    #[inline]
    fn get(&self, v: i64) -> Option<u32> {
        match self {
            VertexIds::Table(ids) => usize::try_from(v)
                .ok()
                .and_then(|v| ids.get(v).copied())
                .filter(|&id| id != NO_ID),
            VertexIds::Map(ids) => ids.get(&v).copied(),
        }
    }

    /// Places vertex `v` (in 0..k, checked) as `id` (below 2**32 - 1).
    #[inline]
    fn insert(&mut self, v: i64, id: u32) {
        match self {
            VertexIds::Table(ids) => {
                if let Some(slot) = usize::try_from(v).ok().and_then(|v| ids.get_mut(v)) {
                    *slot = id;
                }
            }
            VertexIds::Map(ids) => {
                ids.insert(v, id);
            }
        }
    }
}
