//! mbsa: structural analysis of multibody systems.
//!
//! Read a mechanism ([`format`]), count its mobility ([`mobility`]), split it into structural
//! groups ([`structure`]) and find its rigid subsystems ([`rigidity`]). Analyses return
//! serializable values and never print; [`report`] renders them as tables, JSON and DOT.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod budget;
mod cholesky;
pub mod cut;
pub mod diagnostic;
mod elimination;
pub mod exact;
pub mod examples;
pub mod expect;
pub mod export;
pub mod format;
pub mod generate;
pub mod geometry;
pub mod graph;
pub mod import;
pub mod joint;
pub mod mechanism;
pub mod mobility;
pub mod motion;
pub mod numbers;
mod par;
pub mod position;
pub mod repair;
pub mod report;
pub mod rigidity;
pub mod rng;
pub mod structure;
pub mod transform;
pub mod words;
pub mod write;

pub use joint::JointType;
pub use mechanism::{Body, BodyId, Geometry, InputSpec, Joint, JointSpec, Mechanism, Space};
