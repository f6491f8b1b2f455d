//! Geometric rigidity: true mobility, redundant constraints, isolated DOF and rigid clusters from the constraint Jacobian.
