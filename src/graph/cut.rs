//! Cut vertices on the side of a root: the vertices through which some others reach it.

/// The vertices of `n` through which some other vertex reaches `root` only (the cut vertices
/// of `root`'s component, `root` left out; a vertex of another component is never marked),
/// for the undirected multigraph of `edges` (a self-loop joins nothing; parallel edges are a
/// cycle). One iterative depth-first search (Tarjan's low points), linear in the edges, in
/// flat arrays of 32-bit indices: a graph of 10^6 vertices takes tens of megabytes.
pub fn separating(n: usize, edges: &[(u32, u32)], root: usize) -> Vec<bool> {
    let mut sep = vec![false; n];
    if root >= n {
        return sep;
    }
    // Adjacency in compressed rows.
    let mut start = vec![0u32; n + 1];
    for &(a, c) in edges {
        if a != c {
            start[a as usize + 1] += 1;
            start[c as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut next = start[..n].to_vec();
    let mut adj = vec![0u32; start[n] as usize];
    for &(a, c) in edges {
        if a != c {
            adj[next[a as usize] as usize] = c;
            next[a as usize] += 1;
            adj[next[c as usize] as usize] = a;
            next[c as usize] += 1;
        }
    }
    next.copy_from_slice(&start[..n]);
    let mut disc = vec![u32::MAX; n];
    let mut low = vec![0u32; n];
    disc[root] = 0;
    let mut time = 1u32;
    // (vertex, its parent until the edge it was entered by is passed over once: a second edge
    // to the parent is a cycle)
    let mut stack: Vec<(u32, u32)> = vec![(root as u32, u32::MAX)];
    while let Some(&mut (v, ref mut parent)) = stack.last_mut() {
        let v = v as usize;
        if next[v] < start[v + 1] {
            let w = adj[next[v] as usize];
            next[v] += 1;
            if w == *parent {
                *parent = u32::MAX;
                continue;
            }
            let w = w as usize;
            if disc[w] == u32::MAX {
                disc[w] = time;
                low[w] = time;
                time += 1;
                stack.push((w as u32, v as u32));
            } else {
                low[v] = low[v].min(disc[w]);
            }
        } else {
            stack.pop();
            if let Some(&(p, _)) = stack.last() {
                let p = p as usize;
                low[p] = low[p].min(low[v]);
                if p != root && low[v] >= disc[p] {
                    sep[p] = true;
                }
            }
        }
    }
    sep
}

#[cfg(test)]
mod tests {
    use super::separating;

    #[test]
    fn a_chain_separates_at_its_inner_vertices_only() {
        // 0 - 1 - 2 - 3, root 0.
        let sep = separating(4, &[(0, 1), (1, 2), (2, 3)], 0);
        assert_eq!(sep, [false, true, true, false]);
        // Rooted at an end's other side: the root itself is never marked.
        let sep = separating(4, &[(0, 1), (1, 2), (2, 3)], 3);
        assert_eq!(sep, [false, true, true, false]);
    }

    #[test]
    fn a_cycle_has_no_cut_vertex_and_a_pendant_makes_one() {
        // Triangle 0-1-2 with 3 hanging on 2, and 4-5 in another component.
        let edges = [(0, 1), (1, 2), (2, 0), (2, 3), (4, 5)];
        let sep = separating(6, &edges, 0);
        assert_eq!(sep, [false, false, true, false, false, false]);
    }

    #[test]
    fn parallel_edges_are_a_cycle_and_self_loops_join_nothing() {
        // 0 = 1 (two edges) - 2: 1 separates 2; the doubled edge does not make 0 or 1 a cut.
        let sep = separating(3, &[(0, 1), (1, 0), (1, 2), (2, 2)], 0);
        assert_eq!(sep, [false, true, false]);
        let sep = separating(2, &[(0, 1), (1, 0)], 0);
        assert_eq!(sep, [false, false]);
    }

    #[test]
    fn a_long_path_does_not_recurse() {
        let n = 200_000;
        let edges: Vec<(u32, u32)> = (0..n as u32 - 1).map(|v| (v, v + 1)).collect();
        let sep = separating(n, &edges, 0);
        assert!(!sep[0] && !sep[n - 1]);
        assert!(sep[1..n - 1].iter().all(|&s| s));
    }
}
