//! The binary tree collapsed into the 8-wide one at the least surface-area cost, by dynamic
//! programming (Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on GPUs Through
//! Compressed Wide BVHs", HPG 2017, §3.1).
//!
//! The greedy collapse (`collapse.rs`) opens the largest child until a node has eight; it keeps
//! the binary build's leaves as they are. Here every way of cutting the binary tree into wide
//! nodes and leaves is priced, and the cheapest taken. For a binary node `n` of half area `A(n)`
//! over `p(n)` triangles, let `C(n, i)` be the least cost of `n`'s subtree when it may take up
//! to `i` slots of its wide parent:
//!
//! ```text
//! C(n, 1)     = min(C_leaf(n), C_node(n))
//! C(n, i)     = min(C(n, i − 1), D(n, i))                    for i = 2..8
//! C_leaf(n)   = A(n) · c_record · ⌈p(n)/u⌉    if p(n) ≤ the leaf limit, else ∞
//! C_node(n)   = A(n) · c_node + D(n, 8)
//! D(n, j)     = min over 0 < k < j of C(left, k) + C(right, j − k)
//! ```
//!
//! `C_leaf` makes one leaf of the whole subtree (records of `u` triangles: eight for leaves of
//! up to eight, as the binned build prices a tree of such leaves), `C_node` a wide node whose
//! children are the subtree cut into up to eight parts, and `D` shares `j` slots between the
//! two children. A binary leaf is one slot whatever `i`. The table is filled children first
//! (the binary tree is depth first, so in reverse order), eight costs and the choices that gave
//! them per node; the wide tree is then read off from the root.
//!
//! Ylitie et al. build the binary tree down to one triangle a leaf, so that the choice of leaves
//! is the collapse's alone; [`Collapse::Optimal`](super::Collapse) names the largest binary
//! leaf, and `high` uses four, which keeps nearly all of the gain at a fraction of the build
//! time.
//!
//! Costs stay numbers in any scene: a box whose half area is not finite (coordinates near
//! `f32::MAX`, or an infinite extent beside a zero one, whose product is NaN) is priced at
//! `f32::MAX`, sums may reach infinity but never NaN, a subtree becomes a leaf only if it fits
//! one, and every split gives each child at least one slot, so that a node never has more than
//! eight children whatever the costs.

use glam::Vec3;

use super::BinaryBvh;
use super::bins::{records, unit_shift};
use super::collapse::{Reading, push_leaf};
use crate::bvh::node::{WIDTH, WideBvh};

/// The costs the collapse weighs: a wide node's test and a leaf record's, and the largest leaf.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Costs {
    pub node: f32,
    pub record: f32,
    pub max_leaf: usize,
}

/// One binary node's row of the table.
#[derive(Clone, Copy, Debug)]
struct Row {
    /// `C(n, i)` for `i = 1..=8` at `cost[i − 1]`.
    cost: [f32; WIDTH],
    /// `split[j]`: the `k` slots of the left child that give `D(n, j)`, `j = 2..=8`.
    split: [u8; WIDTH + 1],
    /// Bit `i` set where `C(n, i) = C(n, i − 1)`: fewer slots are as cheap.
    fewer: u16,
    /// `C(n, 1)` is a leaf of the whole subtree.
    leaf: bool,
    /// The subtree's triangles: `order[first..first + count]`.
    first: u32,
    count: u32,
}

/// Collapses `binary` (built over `prim_ids`' triangles) into a wide BVH of least cost.
///
/// `triangle(i)` gives the vertices of build primitive `i`, and `prim_ids[i]` its caller's index.
pub(crate) fn collapse_optimal(
    binary: &BinaryBvh,
    costs: Costs,
    triangle: impl Fn(u32) -> [Vec3; 3],
    prim_ids: impl Fn(u32) -> u32,
) -> WideBvh {
    let table = table(binary, costs);
    Reader { binary, table: &table, triangle: &triangle, prim_ids: &prim_ids }.read()
}

/// The table of every node's costs and choices, children before parents.
fn table(binary: &BinaryBvh, costs: Costs) -> Vec<Row> {
    let nodes = &binary.nodes;
    let unit = unit_shift(costs.max_leaf);
    let empty = Row {
        cost: [0.0; WIDTH],
        split: [0; WIDTH + 1],
        fewer: 0,
        leaf: false,
        first: 0,
        count: 0,
    };
    let mut table = vec![empty; nodes.len()];
    for n in (0..nodes.len()).rev() {
        let node = &nodes[n];
        let area = node.bounds.half_area();
        // Not finite (or NaN): the largest price, so that sums never hold a NaN.
        let area = if area.is_finite() { area } else { f32::MAX };
        let fits = |count: u32| count as usize <= costs.max_leaf;
        let leaf_cost = |count: u32| {
            if fits(count) { area * costs.record * records(count, unit) } else { f32::INFINITY }
        };
        if node.is_leaf() {
            let cost = leaf_cost(node.count);
            table[n] = Row {
                cost: [cost; WIDTH],
                leaf: true,
                first: node.first_or_right,
                count: node.count,
                ..empty
            };
            continue;
        }
        let (left, right) = (&table[n + 1], &table[node.first_or_right as usize]);
        // Every split starts at one slot for the left child: a valid cut even if no cost is
        // finite.
        let mut row = Row {
            first: left.first,
            count: left.count + right.count,
            split: [1; WIDTH + 1],
            ..empty
        };
        // D(n, j) for j = 2..=8.
        let mut distribute = [f32::INFINITY; WIDTH + 1];
        for (j, (least, split)) in distribute.iter_mut().zip(&mut row.split).enumerate().skip(2) {
            for k in 1..j {
                let cost = left.cost[k - 1] + right.cost[j - k - 1];
                if cost < *least {
                    (*least, *split) = (cost, k as u8);
                }
            }
        }
        let as_leaf = leaf_cost(row.count);
        let as_node = area * costs.node + distribute[WIDTH];
        row.leaf = fits(row.count) && as_leaf <= as_node;
        row.cost[0] = as_leaf.min(as_node);
        for (i, &shared) in distribute.iter().enumerate().skip(2) {
            if shared < row.cost[i - 2] {
                row.cost[i - 1] = shared;
            } else {
                row.cost[i - 1] = row.cost[i - 2];
                row.fewer |= 1 << i;
            }
        }
        table[n] = row;
    }
    table
}

/// Reads the wide tree off the table.
struct Reader<'a, T, I> {
    binary: &'a BinaryBvh,
    table: &'a [Row],
    triangle: &'a T,
    prim_ids: &'a I,
}

impl<T: Fn(u32) -> [Vec3; 3], I: Fn(u32) -> u32> Reader<'_, T, I> {
    /// The binary nodes that take the slots of `n`'s subtree when it may take up to `i`.
    fn slots(&self, n: usize, i: usize, out: &mut Vec<usize>) {
        if i == 1 || self.binary.nodes[n].is_leaf() {
            out.push(n);
        } else if self.table[n].fewer & (1 << i) != 0 {
            self.slots(n, i - 1, out);
        } else {
            self.distribute(n, i, out);
        }
    }

    /// The binary nodes that take `j` slots shared between `n`'s children.
    fn distribute(&self, n: usize, j: usize, out: &mut Vec<usize>) {
        let k = self.table[n].split[j] as usize;
        self.slots(n + 1, k, out);
        self.slots(self.binary.nodes[n].first_or_right as usize, j - k, out);
    }
}

impl<T: Fn(u32) -> [Vec3; 3], I: Fn(u32) -> u32> Reading for Reader<'_, T, I> {
    fn binary(&self) -> &BinaryBvh {
        self.binary
    }

    /// The table's cut of `node` into up to eight slots.
    fn children(&self, node: usize) -> Vec<usize> {
        let mut children = Vec::with_capacity(WIDTH);
        self.distribute(node, WIDTH, &mut children);
        children
    }

    /// Binary leaves, and the subtrees whose cheapest form is one leaf.
    fn is_leaf(&self, child: usize) -> bool {
        self.table[child].leaf
    }

    /// Writes the triangles of binary node `node`'s subtree as one leaf.
    fn emit_leaf(&self, node: usize, wide: &mut WideBvh) -> u32 {
        let Row { first, count, .. } = self.table[node];
        let prims = &self.binary.order[first as usize..(first + count) as usize];
        push_leaf(wide, prims, self.triangle, self.prim_ids)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::bvh::build::{BinaryNode, BuildSettings, build_triangles, collapse};
    use crate::bvh::node::{Child, decode};
    use crate::bvh::tests::Lcg;

    fn soup(count: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut rng = Lcg(seed);
        (0..count)
            .map(|_| {
                let p = rng.vec() * 10.0;
                let size = 0.05 + rng.next() * rng.next() * 3.0;
                [p, p + rng.vec() * size, p + rng.vec() * size]
            })
            .collect()
    }

    /// The surface-area cost of a wide tree, priced as the collapse prices it: every wide node's
    /// half area times `c_node`, every leaf's half area times `c_record` per record unit.
    fn wide_cost(wide: &WideBvh, costs: Costs) -> f64 {
        let unit = unit_shift(costs.max_leaf);
        fn node(wide: &WideBvh, index: u32, area: f32, costs: Costs, unit: u32) -> f64 {
            let n = &wide.nodes[index as usize];
            let mut cost = area as f64 * costs.node as f64;
            for k in 0..WIDTH {
                let a = n.bounds(k).half_area();
                match decode(n.children[k]) {
                    Child::Empty => {}
                    Child::Node(child) => cost += node(wide, child, a, costs, unit),
                    Child::Leaf(offset) => {
                        let count = wide.leaves.leaf_triangles(offset).count() as u32;
                        cost += a as f64 * costs.record as f64 * records(count, unit) as f64;
                    }
                }
            }
            cost
        }
        node(wide, 0, wide.root.half_area(), costs, unit)
    }

    /// The least cost of `n`'s subtree as one child of a wide node, by listing every cut of it
    /// into at most eight parts: the definition in the module documentation, without its
    /// table.
    fn least_by_listing(nodes: &[BinaryNode], n: usize, costs: Costs) -> f64 {
        let unit = unit_shift(costs.max_leaf);
        let count = |n: usize| -> u32 {
            fn c(nodes: &[BinaryNode], n: usize) -> u32 {
                if nodes[n].is_leaf() {
                    nodes[n].count
                } else {
                    c(nodes, n + 1) + c(nodes, nodes[n].first_or_right as usize)
                }
            }
            c(nodes, n)
        };
        let area = nodes[n].bounds.half_area() as f64;
        let leaf = if count(n) as usize <= costs.max_leaf {
            area * costs.record as f64 * records(count(n), unit) as f64
        } else {
            f64::INFINITY
        };
        if nodes[n].is_leaf() {
            return leaf;
        }
        // Every cut of a subtree into parts: itself, or a cut of each child.
        fn cuts(nodes: &[BinaryNode], n: usize) -> Vec<Vec<usize>> {
            let mut all = vec![vec![n]];
            if !nodes[n].is_leaf() {
                for a in cuts(nodes, n + 1) {
                    for b in cuts(nodes, nodes[n].first_or_right as usize) {
                        if a.len() + b.len() <= WIDTH {
                            all.push([a.clone(), b].concat());
                        }
                    }
                }
            }
            all
        }
        let mut best_children = f64::INFINITY;
        for a in cuts(nodes, n + 1) {
            for b in cuts(nodes, nodes[n].first_or_right as usize) {
                if a.len() + b.len() <= WIDTH {
                    let parts: f64 =
                        a.iter().chain(&b).map(|&m| least_by_listing(nodes, m, costs)).sum();
                    best_children = best_children.min(parts);
                }
            }
        }
        leaf.min(area * costs.node as f64 + best_children)
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-5 * a.abs().max(b.abs())
    }

    #[test]
    fn the_table_holds_the_least_cost_of_every_cut() {
        for seed in 0..12u64 {
            let triangles = soup(10 + seed as usize * 2, seed);
            let max_leaf = [2, 4, 8][seed as usize % 3];
            let costs =
                Costs { node: [1.0, 0.3, 2.5][seed as usize / 3 % 3], record: 1.0, max_leaf };
            let settings =
                BuildSettings { max_leaf_size: 1, flat_limit: 0, ..BuildSettings::MEDIUM };
            let binary = build_triangles(&triangles, &settings);
            let table = table(&binary, costs);
            let listed = least_by_listing(&binary.nodes, 0, costs);
            assert!(
                close(table[0].cost[0] as f64, listed),
                "seed {seed}: {} against {listed}",
                table[0].cost[0]
            );
            // And the tree read off the table costs what the table says (a root that is one
            // leaf is priced as a node over it, as `wide_cost` sees it).
            let wide = collapse_optimal(&binary, costs, |i| triangles[i as usize], |i| i);
            if !table[0].leaf {
                assert!(close(wide_cost(&wide, costs), listed), "seed {seed}");
            }
        }
    }

    #[test]
    fn the_collapse_costs_no_more_than_the_greedy_one() {
        for (seed, max_leaf) in [(1u64, 8usize), (2, 4), (3, 8)] {
            let triangles = soup(4000, seed);
            let settings =
                BuildSettings { max_leaf_size: max_leaf, flat_limit: 0, ..BuildSettings::MEDIUM };
            let binary = build_triangles(&triangles, &settings);
            let costs = Costs { node: 1.0, record: 1.0, max_leaf };
            let greedy = wide_cost(&collapse(&binary, |i| triangles[i as usize], |i| i), costs);
            let optimal = wide_cost(
                &collapse_optimal(&binary, costs, |i| triangles[i as usize], |i| i),
                costs,
            );
            assert!(optimal <= greedy * (1.0 + 1e-6), "seed {seed}: {optimal} against {greedy}");
            // Over finer binary leaves it has more to choose from.
            let fine = build_triangles(&triangles, &BuildSettings { max_leaf_size: 1, ..settings });
            let finer =
                wide_cost(&collapse_optimal(&fine, costs, |i| triangles[i as usize], |i| i), costs);
            assert!(finer < greedy, "seed {seed}: {finer} against {greedy}");
        }
    }
}
