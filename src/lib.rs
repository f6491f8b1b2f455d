//! mbsa: structural analysis of multibody systems.
//!
//! Read a mechanism ([`format`]), count its mobility ([`mobility`]), split it into structural
//! groups ([`structure`]), find other input placements ([`transform`]) and its rigid
//! subsystems ([`rigidity`]). Analyses return serializable values and never print; [`report`]
//! renders them as tables, JSON and Graphviz DOT.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod joint;
pub mod mechanism;

pub use joint::JointType;
pub use mechanism::{Body, BodyId, Geometry, InputSpec, Joint, JointSpec, Mechanism, Space};
