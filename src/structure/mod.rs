//! Structural analysis: the decomposition of a mechanism into ordered structural groups.
