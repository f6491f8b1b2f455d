//! The Chebyshev-Gruebler-Kutzbach mobility count and the connectivity facts around it.
