//! The joint-motion model: the relative twists each joint allows and the constraint rows it imposes, at given or random geometry.
