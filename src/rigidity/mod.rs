//! Rigid subsystems: generic rigidity by counting (pebble game) and geometric rigidity (twist/wrench rank analysis).

pub mod both;
pub mod geometric;
pub mod pebble;
