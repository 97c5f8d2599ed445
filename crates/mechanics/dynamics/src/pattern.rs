//! Where the stage's matrices can be non-zero: one symmetric sparsity pattern over the
//! master matrix (layout order x, q, s), the union over the lossless part, every damping
//! tag and the mass matrix. Everything that runs per frequency works on this fixed pattern,
//! and the exactly decoupled blocks of a suspension are its connected components.

use std::borrow::Cow;
use std::ops::Range;

/// A symmetric sparsity pattern of an n × n matrix in compressed rows, columns sorted in
/// each row. A slot is the index of one stored position; values of a matrix on the pattern
/// are a slice indexed by slot.
#[derive(Clone, Debug, PartialEq)]
pub struct Pattern {
    dim: usize,
    row_start: Vec<usize>,
    row_of: Vec<usize>,
    cols: Vec<usize>,
}

impl Pattern {
    /// The pattern holding every `(row, column)` of `positions` (duplicates allowed, each
    /// below `dim`: the caller guarantees it), and the transposed positions too, so that it
    /// is symmetric.
    pub(crate) fn from_positions(
        dim: usize,
        positions: impl IntoIterator<Item = (usize, usize)>,
    ) -> Self {
        let mut rows: Vec<Vec<usize>> = vec![Vec::new(); dim];
        for (i, j) in positions {
            rows[i].push(j);
            rows[j].push(i);
        }
        let mut row_start = Vec::with_capacity(dim + 1);
        let mut row_of = Vec::new();
        let mut cols = Vec::new();
        row_start.push(0);
        for (i, mut row) in rows.into_iter().enumerate() {
            row.sort_unstable();
            row.dedup();
            row_of.extend(std::iter::repeat_n(i, row.len()));
            cols.extend(row);
            row_start.push(cols.len());
        }
        Pattern {
            dim,
            row_start,
            row_of,
            cols,
        }
    }

    /// Number of rows (and columns).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of stored positions.
    pub fn len(&self) -> usize {
        self.cols.len()
    }

    /// Whether nothing is stored.
    pub fn is_empty(&self) -> bool {
        self.cols.is_empty()
    }

    /// Slots of row `i` (below [`Pattern::dim`]: crate-internal, callers loop over rows
    /// they own).
    pub(crate) fn row_slots(&self, i: usize) -> Range<usize> {
        self.row_start[i]..self.row_start[i + 1]
    }

    /// Columns stored in row `i` (below [`Pattern::dim`]), ascending.
    pub(crate) fn row(&self, i: usize) -> &[usize] {
        &self.cols[self.row_slots(i)]
    }

    /// (row, column) of a slot (below [`Pattern::len`]: crate-internal; outside, see
    /// [`Pattern::positions`] and [`Pattern::get_position`]).
    pub(crate) fn position(&self, slot: usize) -> (usize, usize) {
        (self.row_of[slot], self.cols[slot])
    }

    /// (row, column) of a slot, or `None` for a slot past [`Pattern::len`].
    pub fn get_position(&self, slot: usize) -> Option<(usize, usize)> {
        Some((*self.row_of.get(slot)?, *self.cols.get(slot)?))
    }

    /// (row, column) of every slot, in slot order: zip it with values on the pattern.
    pub fn positions(&self) -> impl ExactSizeIterator<Item = (usize, usize)> + '_ {
        self.row_of.iter().copied().zip(self.cols.iter().copied())
    }

    /// The slot of (i, j), if stored (`None` for a row or column past [`Pattern::dim`]).
    pub fn slot(&self, i: usize, j: usize) -> Option<usize> {
        if i >= self.dim {
            return None;
        }
        let range = self.row_slots(i);
        self.cols[range.clone()]
            .binary_search(&j)
            .ok()
            .map(|k| range.start + k)
    }

    /// Builds a pattern from rows already in compressed form (columns ascending in each
    /// row, no duplicates, and symmetric: the caller guarantees it).
    pub(crate) fn from_sorted_rows(dim: usize, row_start: Vec<usize>, cols: Vec<usize>) -> Self {
        debug_assert_eq!(row_start.len(), dim + 1);
        let mut row_of = Vec::with_capacity(cols.len());
        for i in 0..dim {
            row_of.extend(std::iter::repeat_n(i, row_start[i + 1] - row_start[i]));
        }
        Pattern {
            dim,
            row_start,
            row_of,
            cols,
        }
    }

    /// The slot of the transposed position of every slot: (j, i) for the slot of (i, j).
    /// Linear in the stored positions: visiting the rows in order, the positions (i, j) of
    /// column j come in ascending i, which is the order of row j's columns.
    pub fn transposed_slots(&self) -> Vec<usize> {
        let mut next: Vec<usize> = self.row_start[..self.dim].to_vec();
        self.cols
            .iter()
            .map(|&j| {
                let s = next[j];
                next[j] += 1;
                s
            })
            .collect()
    }

    /// The sub-pattern of the slots `keep` accepts, kept symmetric (a slot stays when it or
    /// its transpose is accepted), and for each of its slots the slot it had here.
    pub fn retain(&self, keep: impl Fn(usize) -> bool) -> (Pattern, Vec<usize>) {
        let accepted: Vec<bool> = (0..self.len()).map(&keep).collect();
        let transposed = self.transposed_slots();
        let mut row_start = Vec::with_capacity(self.dim + 1);
        let mut cols = Vec::new();
        let mut old = Vec::new();
        row_start.push(0);
        for i in 0..self.dim {
            for s in self.row_slots(i) {
                if accepted[s] || accepted[transposed[s]] {
                    cols.push(self.cols[s]);
                    old.push(s);
                }
            }
            row_start.push(cols.len());
        }
        (Pattern::from_sorted_rows(self.dim, row_start, cols), old)
    }

    /// The compressed columns (column pointers, row indices) of the square sub-pattern over
    /// `nodes` (ascending), numbered by `local` (the position of each node among `nodes`,
    /// `usize::MAX` for nodes left out; every node below [`Pattern::dim`]). Rows stay
    /// ascending in each column because the numbering keeps the order.
    pub(crate) fn restricted_columns(
        &self,
        nodes: &[usize],
        local: &[usize],
    ) -> (Vec<usize>, Vec<usize>) {
        let mut col_ptr = Vec::with_capacity(nodes.len() + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for &c in nodes {
            // symmetric: row c lists the rows of column c
            row_idx.extend(
                self.row(c)
                    .iter()
                    .filter_map(|&r| local.get(r).copied().filter(|&l| l != usize::MAX)),
            );
            col_ptr.push(row_idx.len());
        }
        (col_ptr, row_idx)
    }

    /// Connected components of the graph over the nodes `0..n` (n ≤ dim) whose edges are
    /// the stored positions with both ends below n: a label per node, numbered from 0 in
    /// order of each component's lowest node, and the number of components.
    pub(crate) fn components(&self, n: usize) -> (Vec<usize>, usize) {
        const NONE: usize = usize::MAX;
        let mut label = vec![NONE; n];
        let mut count = 0;
        let mut stack = Vec::new();
        for start in 0..n {
            if label[start] != NONE {
                continue;
            }
            label[start] = count;
            stack.push(start);
            while let Some(i) = stack.pop() {
                for &j in self.row(i) {
                    if j < n && label[j] == NONE {
                        label[j] = count;
                        stack.push(j);
                    }
                }
            }
            count += 1;
        }
        (label, count)
    }
}

/// A pattern that holds several models' patterns (those of a parameter's stepped models,
/// which differ where the parameter moves an entry to or from an exact zero): which of
/// them it is, and how each one's slots map into it, so that values on any of the
/// patterns can be compared, differenced and summed on the one.
#[derive(Clone, Debug, PartialEq)]
pub struct CommonPattern {
    base: usize,
    len: usize,
    /// Per pattern: the slot in the base pattern of each of its own slots; `None` for a
    /// pattern equal to the base (the usual case).
    maps: Vec<Option<Vec<usize>>>,
}

impl CommonPattern {
    /// The first of `patterns` that holds every other's positions, with each one's map into
    /// it; `None` when none does (or `patterns` is empty).
    pub fn of(patterns: &[&Pattern]) -> Option<CommonPattern> {
        (0..patterns.len()).find_map(|base| {
            let target = patterns[base];
            let maps = patterns
                .iter()
                .map(|&own| {
                    if own == target {
                        return Some(None);
                    }
                    own.positions()
                        .map(|(i, j)| target.slot(i, j))
                        .collect::<Option<Vec<usize>>>()
                        .map(Some)
                })
                .collect::<Option<Vec<_>>>()?;
            Some(CommonPattern {
                base,
                len: target.len(),
                maps,
            })
        })
    }

    /// The index (in the slice given to [`CommonPattern::of`]) of the pattern that holds
    /// the others.
    pub fn base(&self) -> usize {
        self.base
    }

    /// Values on the `k`-th pattern (one per slot) as values on the base pattern: borrowed
    /// where the `k`-th pattern is the base's, else copied into their slots there with
    /// zeros elsewhere. `None` for `k` past the patterns or values of another length.
    pub fn on_base<'v>(&self, k: usize, values: &'v [f64]) -> Option<Cow<'v, [f64]>> {
        match self.maps.get(k)? {
            None => (values.len() == self.len).then_some(Cow::Borrowed(values)),
            Some(map) => {
                if values.len() != map.len() {
                    return None;
                }
                let mut v = vec![0.0; self.len];
                for (&slot, &x) in map.iter().zip(values) {
                    v[slot] = x;
                }
                Some(Cow::Owned(v))
            }
        }
    }
}

/// Connected components of the graph over `0..n` joining i and j wherever any of
/// `matrices` (each n × n, column-major) has a non-zero (i, j) or (j, i): a label per node
/// (numbered from 0 in order of lowest node) and the number of components. One pass over
/// the stored values, O(n²): for dense storage (the eigenproblem's K_eff and M).
pub(crate) fn dense_components(n: usize, matrices: &[&[f64]]) -> (Vec<usize>, usize) {
    let mut positions = Vec::new();
    for values in matrices {
        for (j, column) in values.chunks_exact(n.max(1)).enumerate().take(n) {
            // (i, j) joins both rows: from_positions adds the transpose
            positions.extend(
                column
                    .iter()
                    .enumerate()
                    .filter(|&(_, &v)| v != 0.0)
                    .map(|(i, _)| (i, j)),
            );
        }
    }
    Pattern::from_positions(n, positions).components(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn components_follow_the_stored_positions() {
        // 0–2 and 1–3 coupled, 4 alone: three components labelled by their lowest node
        let p = Pattern::from_positions(5, [(0, 2), (3, 1), (4, 4), (2, 2)]);
        assert_eq!(p.components(5), (vec![0, 1, 0, 1, 2], 3));
        assert_eq!(p.slot(2, 0), Some(p.row_slots(2).start));
        assert_eq!(p.slot(0, 1), None);
        // only nodes below n count: 0 and 2 are still joined, 3 is cut from 1
        assert_eq!(p.components(3), (vec![0, 1, 0], 2));
        let (rows, cols): (Vec<_>, Vec<_>) = (0..p.len()).map(|s| p.position(s)).unzip();
        assert_eq!(rows, [0, 1, 2, 2, 3, 4]);
        assert_eq!(cols, [2, 3, 0, 2, 1, 4]);
    }

    #[test]
    fn out_of_range_rows_and_slots_are_none_not_panics() {
        let p = Pattern::from_positions(3, [(0, 2), (1, 1)]);
        // (0, 2), (1, 1), (2, 0): three slots in a 3 × 3 pattern
        assert_eq!(p.len(), 3);
        assert_eq!(p.get_position(2), Some((2, 0)));
        assert_eq!(p.get_position(3), None);
        assert_eq!(p.get_position(usize::MAX), None);
        assert_eq!(p.slot(3, 0), None);
        assert_eq!(p.slot(0, 3), None);
        assert_eq!(p.slot(usize::MAX, usize::MAX), None);
        let all: Vec<_> = p.positions().collect();
        assert_eq!(all, [(0, 2), (1, 1), (2, 0)]);
    }

    #[test]
    fn transposes_and_retains_symmetrically() {
        let p = Pattern::from_positions(4, [(0, 2), (3, 1), (1, 1), (2, 3), (0, 0)]);
        let t = p.transposed_slots();
        for (s, &transposed) in t.iter().enumerate() {
            let (i, j) = p.position(s);
            assert_eq!(p.position(transposed), (j, i));
        }
        // keep only (2, 0) and (1, 1): (0, 2) stays as its transpose, nothing else
        let keep = [p.slot(2, 0).unwrap(), p.slot(1, 1).unwrap()];
        let (q, old) = p.retain(|s| keep.contains(&s));
        let kept: Vec<_> = (0..q.len()).map(|s| q.position(s)).collect();
        assert_eq!(kept, [(0, 2), (1, 1), (2, 0)]);
        let before: Vec<_> = old.iter().map(|&s| p.position(s)).collect();
        assert_eq!(before, kept);
    }

    #[test]
    fn a_common_pattern_holds_the_others_and_maps_their_slots() {
        // a diagonal 2 × 2 pattern and the full one: the full one holds both. Its slots in
        // row order are (0,0) 0, (0,1) 1, (1,0) 2, (1,1) 3, so the diagonal's slots (0,0)
        // and (1,1) map to 0 and 3
        let diagonal = Pattern::from_positions(2, [(0, 0), (1, 1)]);
        let full = Pattern::from_positions(2, [(0, 0), (0, 1), (1, 1)]);
        let common = CommonPattern::of(&[&diagonal, &full, &diagonal]).expect("full holds both");
        assert_eq!(common.base(), 1);
        let moved = common.on_base(0, &[2.0, 5.0]).unwrap();
        assert_eq!(&*moved, &[2.0, 0.0, 0.0, 5.0]);
        assert!(matches!(moved, Cow::Owned(_)));
        // the base's own values are borrowed, not copied
        let own = [1.0, 2.0, 3.0, 4.0];
        assert!(matches!(common.on_base(1, &own), Some(Cow::Borrowed(v)) if v == own));
        // values of another length, or a pattern past the list: none
        assert!(common.on_base(0, &own).is_none());
        assert!(common.on_base(3, &own).is_none());
        // equal patterns: the first is the base and no values move
        let same = CommonPattern::of(&[&full, &full]).unwrap();
        assert_eq!(same.base(), 0);
        assert!(matches!(same.on_base(1, &own), Some(Cow::Borrowed(_))));
    }

    #[test]
    fn patterns_none_of_which_holds_the_others_have_no_common_pattern() {
        // (0,1) only in one, (1,1) only in the other
        let a = Pattern::from_positions(2, [(0, 0), (0, 1)]);
        let b = Pattern::from_positions(2, [(0, 0), (1, 1)]);
        assert!(CommonPattern::of(&[&a, &b]).is_none());
        assert!(CommonPattern::of(&[]).is_none());
    }
}
