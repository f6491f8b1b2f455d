//! `mbsa generate`: reproducible mechanism files for benchmarks and tests.

use super::{Failure, emit};
use clap::{Subcommand, ValueEnum};
use mbsa::generate::{self, Variant};
use mbsa::joint::JointType;

/// Generator families.
#[derive(Subcommand, Debug)]
pub enum Family {
    /// Planar Assur-group linkage (the paper's Table 16 family, docs/benchmarks.md).
    ///
    /// A driven crank plus N groups of class 1 (dyad), 2 (triad) or 3 (hexagon) attached at
    /// random to earlier bodies; 2 + 2·class·N bodies. Seed 364 gives Table 16's counts.
    #[command(
        after_help = "Example:\n  mbsa generate assur --class 3 --groups 4 --variant B --seed 364 > iii-4b.toml"
    )]
    Assur {
        /// Assur class: 1, 2 or 3.
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=3))]
        class: u32,
        /// Number of groups.
        #[arg(long)]
        groups: u64,
        /// A: the crank is driven; B: the joint between the two last bodies is driven.
        #[arg(long, value_enum, ignore_case = true, default_value_t = VariantArg::A)]
        variant: VariantArg,
        /// Random seed (SplitMix64).
        #[arg(long, default_value_t = 364)]
        seed: u64,
        /// The spatial counterpart: every pair a universal joint but the revolute crank
        /// (not from the paper; same bodies, pairs and groups).
        #[arg(long)]
        spatial: bool,
    },
    /// Random count-determined mechanism with mixed joint types.
    #[command(
        after_help = "Example:\n  mbsa generate random --bodies 100000 --planar --seed 1 > big.toml"
    )]
    Random {
        /// Number of bodies, the frame included.
        #[arg(long)]
        bodies: u64,
        /// Planar (B = 3) instead of spatial.
        #[arg(long)]
        planar: bool,
        /// Random seed (SplitMix64).
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Stewart platforms stacked on U-P-S legs (spatial; 13 bodies per stage, one group each).
    #[command(after_help = "Example:\n  mbsa generate stewart --stages 1000 > tower.toml")]
    Stewart {
        /// Number of stacked platforms.
        #[arg(long)]
        stages: u64,
    },
    /// Open serial chain: body k joined to body k + 1 (the frame is body 1).
    #[command(after_help = "Example:\n  mbsa generate chain --bodies 100000 --joint R > arm.toml")]
    Chain {
        /// Number of bodies, the frame included.
        #[arg(long)]
        bodies: u64,
        /// Joint kind (a code or long name from `mbsa joints`).
        #[arg(long, default_value = "R", value_parser = parse_kind)]
        joint: JointType,
        /// Planar (B = 3) instead of spatial.
        #[arg(long)]
        planar: bool,
        /// Drive every DOF (a determined chain) instead of none.
        #[arg(long)]
        driven: bool,
    },
    /// Star: every body joined to the frame, each by its own joint or all by one shared joint.
    #[command(
        after_help = "Example:\n  mbsa generate star --bodies 20000 --joint S --shared > hub.toml"
    )]
    Star {
        /// Number of bodies, the frame included.
        #[arg(long)]
        bodies: u64,
        /// Joint kind (a code or long name from `mbsa joints`).
        #[arg(long, default_value = "R", value_parser = parse_kind)]
        joint: JointType,
        /// Planar (B = 3) instead of spatial.
        #[arg(long)]
        planar: bool,
        /// One multiple joint naming every body instead of one joint per body.
        #[arg(long)]
        shared: bool,
        /// Drive every DOF (a determined star) instead of none.
        #[arg(long)]
        driven: bool,
    },
}

fn parse_kind(text: &str) -> Result<JointType, String> {
    JointType::parse(text).ok_or_else(|| format!("unknown joint kind `{text}` (see `mbsa joints`)"))
}

/// `--variant` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum VariantArg {
    /// Crank driven.
    #[value(name = "A")]
    A,
    /// Last pair driven.
    #[value(name = "B")]
    B,
}

/// Run a generator and print the TOML file.
pub fn run(family: &Family) -> Result<(), Failure> {
    let size = match *family {
        Family::Assur { class, groups, .. } => generate::Size::Assur { class, groups },
        Family::Random { bodies, planar, .. } => generate::Size::Random { bodies, planar },
        Family::Stewart { stages } => generate::Size::Stewart { stages },
        Family::Chain { bodies, .. } | Family::Star { bodies, .. } => {
            generate::Size::Tree { bodies }
        }
    };
    let joints = generate::estimated_joints(size);
    super::budget()
        .check_memory(joints.saturating_mul(generate::BYTES_PER_JOINT), || {
            format!("generating {joints} joints")
        })
        .map_err(|e| super::budget_failure(&e))?;
    let m = match *family {
        Family::Assur {
            class,
            groups,
            variant,
            seed,
            spatial,
        } => {
            let v = match variant {
                VariantArg::A => Variant::A,
                VariantArg::B => Variant::B,
            };
            if spatial {
                generate::assur_spatial(class, groups, seed, v)
            } else {
                generate::assur(class, groups, seed, v)
            }
        }
        Family::Random {
            bodies,
            planar,
            seed,
        } => generate::random(bodies, planar, seed).map(|(m, _)| m),
        Family::Stewart { stages } => generate::stewart_stack(stages),
        Family::Chain {
            bodies,
            joint,
            planar,
            driven,
        } => generate::serial_chain(bodies, joint, planar, driven),
        Family::Star {
            bodies,
            joint,
            planar,
            shared,
            driven,
        } => generate::star(bodies, joint, planar, shared, driven),
    }
    .map_err(|e| Failure::Input(format!("error: {e}")))?;
    emit(&generate::to_toml(&m))
}
