//! Strongly connected components (Tarjan, iterative) over a CSR adjacency.

/// Iterative Tarjan SCC over the nodes with `active` set, CSR adjacency `adj[start[v]..start[v+1]]`.
/// Components come out in reverse topological order (a component after everything it reaches).
pub fn tarjan(start: &[usize], adj: &[u32], active: &[bool]) -> Vec<Vec<usize>> {
    let (members, bounds) = tarjan_flat(start, adj, active);
    bounds
        .windows(2)
        .map(|w| members[w[0]..w[1]].iter().map(|&x| x as usize).collect())
        .collect()
}

/// [`tarjan`] with the components in one array: component `c` is
/// `members[bounds[c]..bounds[c + 1]]` (same order, same members in the same order; one
/// allocation instead of one per component, 10^6 of them at 10^6 bodies). A component is
/// listed as it comes off the stack: its root (the first of it reached) last.
pub fn tarjan_flat(start: &[usize], adj: &[u32], active: &[bool]) -> (Vec<u32>, Vec<usize>) {
    let n = active.len();
    const UNSEEN: usize = usize::MAX;
    let mut index = vec![UNSEEN; n];
    let mut low = vec![0usize; n];
    let mut on_stack = vec![false; n];
    let mut stack: Vec<usize> = Vec::new();
    let mut call: Vec<(usize, usize)> = Vec::new();
    let mut next = 0usize;
    let mut members: Vec<u32> = Vec::new();
    let mut bounds = vec![0usize];
    for root in 0..n {
        if !active[root] || index[root] != UNSEEN {
            continue;
        }
        index[root] = next;
        low[root] = next;
        next += 1;
        stack.push(root);
        on_stack[root] = true;
        call.push((root, start[root]));
        while let Some(top) = call.last_mut() {
            let v = top.0;
            if top.1 < start[v + 1] {
                let w = adj[top.1] as usize;
                top.1 += 1;
                if !active[w] {
                    continue;
                }
                if index[w] == UNSEEN {
                    index[w] = next;
                    low[w] = next;
                    next += 1;
                    stack.push(w);
                    on_stack[w] = true;
                    call.push((w, start[w]));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
            } else {
                call.pop();
                if let Some(&(p, _)) = call.last() {
                    low[p] = low[p].min(low[v]);
                }
                if low[v] == index[v] {
                    loop {
                        let w = stack.pop().expect("v is still on the stack");
                        on_stack[w] = false;
                        members.push(w as u32);
                        if w == v {
                            break;
                        }
                    }
                    bounds.push(members.len());
                }
            }
        }
    }
    (members, bounds)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tarjan_finds_cycles_dependencies_first() {
        // 0 -> 1 -> 2 -> 1, 3 isolated.
        let start = [0, 1, 2, 3, 3];
        let adj = [1u32, 2, 1];
        let sccs = tarjan(&start, &adj, &[true; 4]);
        let mut sorted: Vec<Vec<usize>> = sccs
            .iter()
            .map(|c| {
                let mut c = c.clone();
                c.sort();
                c
            })
            .collect();
        assert_eq!(sorted[0], vec![1, 2]);
        assert_eq!(sorted[1], vec![0]);
        sorted.sort();
        assert_eq!(sorted, vec![vec![0], vec![1, 2], vec![3]]);
    }

    /// The order the callers rely on: components completed sinks first, each listed from the
    /// top of the stack down to its root; an inactive node is neither a root nor reached.
    #[test]
    fn tarjan_flat_lists_each_component_root_last() {
        // 0 -> 1 -> 2 -> 0, 2 -> 3 -> 4 -> 3, 4 -> 5 (inactive) -> 0.
        let start = [0, 1, 2, 4, 5, 7, 8];
        let adj = [1u32, 2, 0, 3, 4, 3, 5, 0];
        let mut active = [true; 6];
        active[5] = false;
        let (members, bounds) = tarjan_flat(&start, &adj, &active);
        assert_eq!(bounds, vec![0, 2, 5]);
        assert_eq!(members, vec![4, 3, 2, 1, 0]);
    }
}
