//! The encoder's walk (traversal.py's `_Walk`): the decoder's loop with each read replaced by
//! the mesh's answer, recording the four streams.

use super::boundary::Boundary;
use super::{
    edge, ends, first_smallest, GATE_NONE, MAX_VALUES, TIP_FAR, TIP_NEW, TIP_NEXT, TIP_PREV,
};

/// The streams of a face table's walk, the values of Python's `_Walk`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Walked {
    /// The ops stream for each `corner_order` (0: from the gate, 1: from the smallest corner).
    pub ops: [Vec<i64>; 2],
    /// `degree - 3` of each face in walk order, or nothing where every face is a triangle.
    pub degrees: Vec<i64>,
    /// The NEW tips' residuals.
    pub new_residuals: Vec<i64>,
    /// The FAR tips' residuals.
    pub references: Vec<i64>,
    /// The input row of each walked face, in walk order.
    pub order: Vec<i64>,
}

/// The walk of `table` (row-major, `width` entries a row; negative entries are padding, dropped
/// wherever they are) over `k` vertices: the same streams and order as the Python reference.
///
/// `None` where the input is outside what this port handles, so that the caller runs the
/// reference (which raises what it raises): a row of fewer than 3 corners, a vertex `>= k`,
/// `k > 2**32`, or a table of more than [`MAX_VALUES`] entries. Memory: tables of `k` entries, as the reference's `bytearray(k)`.
pub fn encode(table: &[i64], width: usize, k: u64) -> Option<Walked> {
    if width == 0 || table.len() % width != 0 || table.len() > MAX_VALUES || k > 1 << 32 {
        return None;
    }
    let rows = Rows::new(table, width, k)?;
    let mut walk = EncoderWalk::new(rows, k as usize);
    walk.run();
    Some(walk.finish())
}

/// The face rows, padding dropped, as one array of corners and each row's start.
struct Rows {
    corners: Vec<u32>,
    starts: Vec<usize>,
}

impl Rows {
    fn new(table: &[i64], width: usize, k: u64) -> Option<Self> {
        let mut corners = Vec::with_capacity(table.len());
        let mut starts = vec![0];
        for row in table.chunks_exact(width) {
            for &v in row {
                if v >= 0 {
                    if v as u64 >= k {
                        return None;
                    }
                    corners.push(v as u32);
                }
            }
            if corners.len() - starts[starts.len() - 1] < 3 {
                return None;
            }
            starts.push(corners.len());
        }
        Some(Rows { corners, starts })
    }

    fn len(&self) -> usize {
        self.starts.len() - 1
    }

    fn row(&self, f: usize) -> &[u32] {
        &self.corners[self.starts[f]..self.starts[f + 1]]
    }
}

/// Per directed edge, the faces with that edge (consecutive corners), each once, the input's
/// first last: the walk pops the visited ones off the end as it meets them, so its searches
/// together take time linear in the corners. The edges x -> y are sorted by (x, y) into slots;
/// a vertex's slots are found by its first slot and searched by y (a vertex of many edges, as
/// a fan's hub, costs a binary search, not a scan).
struct FacesWith {
    /// each vertex's first slot (k + 1 entries)
    first_slot: Vec<usize>,
    /// each slot's y, and its range in `faces`: its start, and its end, which moves down as
    /// faces pop
    slot_y: Vec<u32>,
    start: Vec<usize>,
    end: Vec<usize>,
    faces: Vec<u32>,
}

impl FacesWith {
    fn new(rows: &Rows, k: usize) -> Self {
        let mut pairs: Vec<(u64, u32)> = Vec::with_capacity(rows.corners.len());
        for f in 0..rows.len() {
            let row = rows.row(f);
            let n = row.len();
            for j in 0..n {
                pairs.push((edge(row[j], row[(j + 1) % n]), f as u32));
            }
        }
        // by edge, then the faces from the last to the first; an edge twice in a face once
        pairs.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1)));
        pairs.dedup();
        let mut with = FacesWith {
            first_slot: vec![0; k + 1],
            slot_y: Vec::new(),
            start: Vec::new(),
            end: Vec::new(),
            faces: Vec::with_capacity(pairs.len()),
        };
        let mut previous_key = None;
        for (key, f) in pairs {
            if previous_key != Some(key) {
                previous_key = Some(key);
                let (x, y) = ends(key);
                with.first_slot[x as usize + 1] += 1;
                with.slot_y.push(y);
                with.start.push(with.faces.len());
                with.end.push(with.faces.len());
            }
            with.faces.push(f);
            let last = with.end.len() - 1;
            with.end[last] += 1;
        }
        for x in 0..k {
            with.first_slot[x + 1] += with.first_slot[x];
        }
        with
    }

    /// The first unvisited face with the edge x -> y, visited ones popped for good.
    fn first_unvisited(&mut self, x: u32, y: u32, done: &[bool]) -> Option<usize> {
        let (low, high) = (self.first_slot[x as usize], self.first_slot[x as usize + 1]);
        let slot = low + self.slot_y[low..high].binary_search(&y).ok()?;
        let (start, end) = (self.start[slot], &mut self.end[slot]);
        while *end > start && done[self.faces[*end - 1] as usize] {
            *end -= 1;
        }
        (*end > start).then(|| self.faces[*end - 1] as usize)
    }
}

/// A face reached across a gate: where its op is in the ops stream, whether it is flipped, the
/// position of the walk's first corner in the stored row and of the smallest in the walk's
/// cycle, and its degree; the op is finished once the corner order is chosen.
struct GateOp {
    position: usize,
    flipped: bool,
    start: usize,
    smallest: usize,
    n: usize,
}

struct EncoderWalk {
    rows: Rows,
    faces_with: FacesWith,
    polygons: bool,
    done: Vec<bool>,
    seen: Vec<bool>,
    boundary: Boundary,
    ops: Vec<i64>,
    gate_ops: Vec<GateOp>,
    degrees: Vec<i64>,
    new_residuals: Vec<i64>,
    references: Vec<i64>,
    order: Vec<i64>,
    last_new: i64,
}

impl EncoderWalk {
    fn new(rows: Rows, k: usize) -> Self {
        let m = rows.len();
        let polygons = (0..m).any(|f| rows.row(f).len() != 3);
        EncoderWalk {
            faces_with: FacesWith::new(&rows, k),
            rows,
            polygons,
            done: vec![false; m],
            seen: vec![false; k],
            boundary: Boundary::new(k, 2 * m),
            ops: Vec::new(),
            gate_ops: Vec::new(),
            degrees: Vec::new(),
            new_residuals: Vec::new(),
            references: Vec::new(),
            order: Vec::with_capacity(m),
            last_new: -1,
        }
    }

    fn run(&mut self) {
        let m = self.rows.len();
        let mut next_seed = 0;
        let mut cycle: Vec<u32> = Vec::new();
        while self.order.len() < m {
            let Some(gate) = self.boundary.gates.pop() else {
                // a seed: the first face not visited, corners as stored, all tips
                while self.done[next_seed] {
                    next_seed += 1;
                }
                self.visit(next_seed);
                cycle.clear();
                cycle.extend_from_slice(self.rows.row(next_seed));
                let mut previous = 0;
                for (j, &w) in cycle.iter().enumerate() {
                    self.tip(w, previous, cycle[0], j == 0);
                    previous = w;
                }
                self.boundary.attach(&cycle, 0);
                continue;
            };
            if !self.boundary.is_open(gate) {
                continue;
            }
            let (a, b) = ends(gate);
            let Some((f, start, flipped)) = self.across(a, b) else {
                self.ops.push(GATE_NONE);
                continue;
            };
            self.visit(f);
            let row = self.rows.row(f);
            let n = row.len();
            cycle.clear();
            cycle.extend((0..n).map(|j| row[(start + j) % n]));
            // the gate op is finished by ops_for: it takes the first tip's op in
            self.gate_ops.push(GateOp {
                position: self.ops.len(),
                flipped,
                start,
                smallest: first_smallest(&cycle),
                n,
            });
            let mut previous = cycle[1];
            for &w in &cycle[2..] {
                self.tip(w, previous, cycle[0], false);
                previous = w;
            }
            self.boundary.attach(&cycle, 1);
        }
    }

    fn visit(&mut self, f: usize) {
        self.done[f] = true;
        self.order.push(f as i64);
        if self.polygons {
            self.degrees.push(self.rows.row(f).len() as i64 - 3);
        }
    }

    /// The op of the tip w: NEW, PREV, NEXT or FAR, in that order of preference.
    fn tip(&mut self, w: u32, previous: u32, first: u32, is_first: bool) {
        if !self.seen[w as usize] {
            self.seen[w as usize] = true;
            self.ops.push(TIP_NEW);
            self.new_residuals.push(i64::from(w) - self.last_new - 1);
            self.last_new = i64::from(w);
        } else if !is_first && self.boundary.newest_into(previous) == Some(w) {
            self.ops.push(TIP_PREV);
        } else if !is_first && self.boundary.newest_out_of(first) == Some(w) {
            self.ops.push(TIP_NEXT);
        } else {
            self.ops.push(TIP_FAR);
            self.references.push(i64::from(w) - i64::from(previous));
        }
    }

    /// The first unvisited face, in the input's order, with the consecutive corners b, a (the
    /// gate face's orientation), else a, b: (face, corner where the walk starts, flipped).
    fn across(&mut self, a: u32, b: u32) -> Option<(usize, usize, bool)> {
        for (first, second, flipped) in [(b, a, false), (a, b, true)] {
            if let Some(f) = self.faces_with.first_unvisited(first, second, &self.done) {
                let row = self.rows.row(f);
                let n = row.len();
                // the first such corner, as the face's corners are stored
                if let Some(j) = (0..n).find(|&j| row[j] == first && row[(j + 1) % n] == second) {
                    return Some((f, j, flipped));
                }
            }
        }
        None
    }

    /// The streams, the gate ops finished for each corner order.
    fn finish(self) -> Walked {
        let ops = [0, 1].map(|corner_order| {
            let mut ops = self.ops.clone();
            for gate in &self.gate_ops {
                let rotation = if corner_order == 0 {
                    gate.start
                } else {
                    (gate.start + gate.smallest) % gate.n
                };
                ops[gate.position] += 1 + 8 * rotation as i64 + 4 * i64::from(gate.flipped);
            }
            ops
        });
        Walked {
            ops,
            degrees: self.degrees,
            new_residuals: self.new_residuals,
            references: self.references,
            order: self.order,
        }
    }
}
