//! The mesh relations of spec section 6.2 that U1's predictors follow, as
//! `tuckercodec/model/topology.py` makes them: the breadth-first forest of the face edges
//! (predictor 1's parents) and predictor 2's steps and sources.

/// Predictor 2's phases (`MEAN_PHASES`): a vertex's rank among the vertices of its depth, in
/// the order of the walk, modulo this.
pub const MEAN_PHASES: usize = 8;

/// What a face table is refused for here: a caller's error (the decoder and the encoder only
/// pass tables that follow the rule of `face_table_problem`), never a file's.
pub type TopologyError = String;

/// The breadth-first walk of the face edges over every component at once (as from a virtual
/// root whose neighbours are each component's smallest vertex, ascending), with the adjacency
/// it walked: the walk, depths and parents of `_mesh_forest`, in the mesh's own numbering.
#[derive(Debug, Clone)]
pub struct Forest {
    /// K, the number of vertices (those on no edge are roots outside the walk).
    pub vertex_count: usize,
    /// CSR rows of the undirected simple graph: `indices[indptr[v]..indptr[v + 1]]`, ascending.
    pub indptr: Vec<usize>,
    pub indices: Vec<u32>,
    /// The vertices on an edge, in the order the walk reaches them.
    pub walk: Vec<u32>,
    /// Where each depth ends in the walk: `[0, end of depth 0, end of depth 1, ...]`
    /// (`[0, 0]` without edges).
    pub level_ends: Vec<usize>,
    /// Each vertex's parent, or -1.
    pub parents: Vec<i64>,
    /// Each vertex's depth (0 for roots and for vertices on no edge).
    pub depth: Vec<u32>,
}

/// The edges of a padded face table (`face_edges`): consecutive corners, and the last real
/// corner back to the first; a `-1` ends a row. Degenerate edges `a == a` are dropped.
fn proper_edges(
    faces: &[i64],
    width: usize,
    vertex_count: usize,
) -> Result<Vec<(u32, u32)>, TopologyError> {
    if vertex_count > u32::MAX as usize {
        return Err(format!(
            "{vertex_count} vertices: more than the core indexes"
        ));
    }
    let mut edges = Vec::new();
    if width == 0 {
        return Ok(edges);
    }
    let check = |value: i64| -> Result<u32, TopologyError> {
        if value < 0 || value as u64 >= vertex_count as u64 {
            Err(format!(
                "a face index {value} outside 0..{}",
                vertex_count as i64 - 1
            ))
        } else {
            Ok(value as u32)
        }
    };
    for row in faces.chunks_exact(width) {
        for corner in 0..width {
            let a = row[corner];
            if a < 0 {
                continue;
            }
            let mut b = if corner + 1 < width {
                row[corner + 1]
            } else {
                row[0]
            };
            if b < 0 {
                b = row[0];
            }
            let (a, b) = (check(a)?, check(b)?);
            if a != b {
                edges.push((a, b));
            }
        }
    }
    Ok(edges)
}

impl Forest {
    /// The forest of an (M, `width`) face table given row after row, `-1` after a row's real
    /// corners. Every index must lie in 0..`vertex_count` (an error otherwise, not a panic).
    pub fn new(faces: &[i64], width: usize, vertex_count: usize) -> Result<Self, TopologyError> {
        if width != 0 && faces.len() % width != 0 {
            return Err("the face table is not a whole number of rows".to_string());
        }
        let edges = proper_edges(faces, width, vertex_count)?;
        let (indptr, indices) = adjacency(&edges, vertex_count);
        drop(edges);
        let (walk, level_ends, parents, depth) = walk(&indptr, &indices, vertex_count);
        Ok(Forest {
            vertex_count,
            indptr,
            indices,
            walk,
            level_ends,
            parents,
            depth,
        })
    }

    /// The forest's number of depths, 0 included (1 for a mesh without edges).
    pub fn levels(&self) -> usize {
        self.level_ends.len() - 1
    }

    /// Vertex `v`'s neighbours, ascending.
    pub fn neighbours(&self, v: usize) -> &[u32] {
        &self.indices[self.indptr[v]..self.indptr[v + 1]]
    }

    /// Predictor 2's order and sources (`MeanSteps` of `_Forest.mean_steps`).
    pub fn mean_steps(&self) -> MeanStepsArrays {
        let levels = self.levels();
        let steps = levels.saturating_sub(1) * MEAN_PHASES;
        let mut step_of = vec![0usize; self.vertex_count];
        for depth in 0..levels {
            let (start, stop) = (self.level_ends[depth], self.level_ends[depth + 1]);
            for (rank, &v) in self.walk[start..stop].iter().enumerate() {
                step_of[v as usize] = depth * MEAN_PHASES + rank % MEAN_PHASES;
            }
        }
        // the rows of depth >= 1 by (depth, phase, walk order): a stable counting sort
        let first = self.level_ends.get(1).copied().unwrap_or(0);
        let predicted = &self.walk[first..];
        let mut step_ends = vec![0usize; steps + 1];
        for &v in predicted {
            step_ends[step_of[v as usize] - MEAN_PHASES + 1] += 1;
        }
        for s in 0..steps {
            step_ends[s + 1] += step_ends[s];
        }
        let mut fill = step_ends.clone();
        let mut rows = vec![0u32; predicted.len()];
        for &v in predicted {
            let slot = &mut fill[step_of[v as usize] - MEAN_PHASES];
            rows[*slot] = v;
            *slot += 1;
        }
        let mut sources = Vec::new();
        let mut anchors = Vec::new();
        let mut source_ends = Vec::with_capacity(rows.len() + 1);
        source_ends.push(0usize);
        for &v in &rows {
            let mine = step_of[v as usize];
            let depth = mine / MEAN_PHASES;
            for &w in self.neighbours(v as usize) {
                let theirs = step_of[w as usize];
                let upper = theirs / MEAN_PHASES + 1 == depth;
                if upper || (theirs / MEAN_PHASES == depth && theirs < mine) {
                    let parent = self.parents[w as usize];
                    sources.push(w);
                    anchors.push(if upper && parent >= 0 {
                        parent as u32
                    } else {
                        w
                    });
                }
            }
            source_ends.push(sources.len());
        }
        MeanStepsArrays {
            rows,
            step_ends,
            sources,
            anchors,
            source_ends,
            levels,
        }
    }
}

/// Predictor 2's steps as arrays (the fields of `MeanSteps`, in the mesh's numbering).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeanStepsArrays {
    pub rows: Vec<u32>,
    pub step_ends: Vec<usize>,
    pub sources: Vec<u32>,
    pub anchors: Vec<u32>,
    pub source_ends: Vec<usize>,
    pub levels: usize,
}

/// The CSR rows of the simple undirected graph of `edges`, each row ascending and without
/// repeats.
fn adjacency(edges: &[(u32, u32)], vertex_count: usize) -> (Vec<usize>, Vec<u32>) {
    let mut indptr = vec![0usize; vertex_count + 1];
    for &(a, b) in edges {
        indptr[a as usize + 1] += 1;
        indptr[b as usize + 1] += 1;
    }
    for v in 0..vertex_count {
        indptr[v + 1] += indptr[v];
    }
    let mut fill = indptr.clone();
    let mut indices = vec![0u32; indptr[vertex_count]];
    for &(a, b) in edges {
        indices[fill[a as usize]] = b;
        fill[a as usize] += 1;
        indices[fill[b as usize]] = a;
        fill[b as usize] += 1;
    }
    // each row sorted and its repeats dropped, compacted towards the front
    let mut write = 0usize;
    let mut start = 0usize;
    for v in 0..vertex_count {
        let stop = indptr[v + 1];
        indices[start..stop].sort_unstable();
        let row_start = write;
        for read in start..stop {
            let value = indices[read];
            if write == row_start || indices[write - 1] != value {
                indices[write] = value;
                write += 1;
            }
        }
        indptr[v] = row_start;
        start = stop;
    }
    indptr[vertex_count] = write;
    indices.truncate(write);
    (indptr, indices)
}

type Walk = (Vec<u32>, Vec<usize>, Vec<i64>, Vec<u32>);

/// The first-in-first-out walk from every component's smallest vertex at once.
fn walk(indptr: &[usize], indices: &[u32], vertex_count: usize) -> Walk {
    let has_edges = |v: usize| indptr[v + 1] > indptr[v];
    // each component's smallest vertex: a flood from each vertex not yet reached, in order
    let mut reached = vec![false; vertex_count];
    let mut roots = Vec::new();
    let mut stack = Vec::new();
    for s in 0..vertex_count {
        if reached[s] || !has_edges(s) {
            continue;
        }
        roots.push(s as u32);
        reached[s] = true;
        stack.push(s as u32);
        while let Some(u) = stack.pop() {
            for &w in &indices[indptr[u as usize]..indptr[u as usize + 1]] {
                if !reached[w as usize] {
                    reached[w as usize] = true;
                    stack.push(w);
                }
            }
        }
    }
    reached.fill(false);
    let mut parents = vec![-1i64; vertex_count];
    let mut depth = vec![0u32; vertex_count];
    let mut order = Vec::with_capacity(vertex_count);
    for &r in &roots {
        reached[r as usize] = true;
        order.push(r);
    }
    let mut head = 0;
    while head < order.len() {
        let u = order[head] as usize;
        head += 1;
        for &w in &indices[indptr[u]..indptr[u + 1]] {
            if !reached[w as usize] {
                reached[w as usize] = true;
                parents[w as usize] = u as i64;
                depth[w as usize] = depth[u] + 1;
                order.push(w);
            }
        }
    }
    // [0, end of depth 0, end of depth 1, ...]: the walk meets the depths in order
    let mut level_ends = vec![0usize];
    let mut current = 0u32;
    for (position, &v) in order.iter().enumerate() {
        if depth[v as usize] != current {
            level_ends.push(position);
            current = depth[v as usize];
        }
    }
    level_ends.push(order.len());
    (order, level_ends, parents, depth)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walk_of_two_components_and_a_lone_vertex() {
        // a square 0-1-2-3 and a triangle 5-6-7, vertex 4 on no face
        let faces = [0, 1, 2, 3, 5, 6, 7, -1];
        let forest = Forest::new(&faces, 4, 8).unwrap();
        assert_eq!(forest.parents, vec![-1, 0, 1, 0, -1, -1, 5, 5]);
        assert_eq!(forest.walk, vec![0, 5, 1, 3, 6, 7, 2]);
        assert_eq!(forest.level_ends, vec![0, 2, 6, 7]);
        assert_eq!(forest.levels(), 3);
        assert_eq!(forest.neighbours(0), &[1, 3]);
    }

    #[test]
    fn no_edges() {
        let forest = Forest::new(&[1, 1, 1], 3, 4).unwrap();
        assert_eq!(forest.levels(), 1);
        assert_eq!(forest.parents, vec![-1; 4]);
        let steps = forest.mean_steps();
        assert!(steps.rows.is_empty());
        assert_eq!(steps.step_ends, vec![0]);
        assert_eq!(steps.source_ends, vec![0]);
        let empty = Forest::new(&[], 3, 0).unwrap();
        assert_eq!(empty.levels(), 1);
    }

    #[test]
    fn bad_indices_are_errors() {
        assert!(Forest::new(&[0, 1, 5], 3, 3).is_err());
        assert!(Forest::new(&[-1, 0, 1], 3, 3).is_err()); // padding first: no corner to close on
        assert!(Forest::new(&[0, 1], 3, 3).is_err());
    }

    #[test]
    fn mean_steps_of_a_fan() {
        // a fan around 0: 0-1-2, 0-2-3, 0-3-4
        let faces = [0, 1, 2, 0, 2, 3, 0, 3, 4];
        let forest = Forest::new(&faces, 3, 5).unwrap();
        let steps = forest.mean_steps();
        assert_eq!(steps.rows, vec![1, 2, 3, 4]); // depth 1, phases 0..3
        assert_eq!(steps.step_ends, vec![0, 1, 2, 3, 4, 4, 4, 4, 4]);
        // 1: parent 0; 2: 0 and 1 (same depth, lower phase); 3: 0, 2; 4: 0, 3
        assert_eq!(steps.sources, vec![0, 0, 1, 0, 2, 0, 3]);
        assert_eq!(steps.anchors, vec![0, 0, 1, 0, 2, 0, 3]);
        assert_eq!(steps.source_ends, vec![0, 1, 3, 5, 7]);
    }
}
