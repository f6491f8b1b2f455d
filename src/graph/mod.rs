//! Graph algorithms with no mechanism knowledge: maximum flow and b-matching on a three-layer
//! network ([`flow`]), strongly connected components ([`scc`]), the cut vertices on a root's
//! side ([`cut`]). The structural analysis, the
//! exact factorization and the transformations all use them from here.

pub mod cut;
pub mod flow;
pub mod scc;
