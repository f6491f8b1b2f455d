//! `mbsa solve` and `mbsa assemble`: the position level.

use super::{Failure, FileArg, emit, load, load_with_inputs};
use clap::{Args, ValueEnum};
use mbsa::Mechanism;
use mbsa::position::inputs::{self, Value};
use mbsa::position::sweep::{self, Method};
use mbsa::position::{
    ClosureStatus, Configuration, NewtonOptions, Pose, PositionModel, SolveError, SolveReport,
};
use mbsa::structure::{self, Library};
use std::io::Write;

/// Output formats of `mbsa solve`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SolveFormat {
    /// Tables for people.
    Table,
    /// JSON (poses, joint values, steps).
    Json,
    /// The mechanism file at the solved configuration (joint origins and axes moved).
    Toml,
}

/// Options of `mbsa solve`.
#[derive(Args, Debug, Clone)]
pub struct SolveArgs {
    /// Replace the file's driven inputs, as `analyze` and `transform` take them: joint ids or
    /// body pairs, `:n` for n DOF (e.g. `1-2,1-13,A:2`); each starts at value 0 (the file's
    /// configuration) unless `--set` gives one.
    #[arg(long)]
    pub inputs: Option<String>,
    /// Input value `JOINT=VALUE[,VALUE...]` (repeatable): JOINT is a joint id or a body pair;
    /// angles in degrees unless written `0.5rad`, slides in file lengths; measured from the
    /// file's configuration. A joint not driven in the file becomes driven. A joint of several
    /// DOF takes its values in the order docs/format.md gives (C: the slide, then the turn; PL:
    /// the two slides, then the turn; S: turns about world x, y, z); fewer values drive its
    /// first DOF, and a note says which.
    #[arg(long = "set", value_name = "JOINT=VALUE")]
    pub set: Vec<String>,
    /// Trace a motion `JOINT=FROM..TO:STEP`, each step starting from the previous one; stops
    /// at a dead point or a branch change.
    #[arg(long, value_name = "JOINT=FROM..TO:STEP")]
    pub sweep: Option<String>,
    /// Project the starting configuration onto the constraints first (least change); the
    /// inputs `--set` does not give then hold the values the assembly left them at.
    #[arg(long)]
    pub assemble: bool,
    /// Start from these poses (JSON, as `--format json` writes them) instead of the file's
    /// configuration.
    #[arg(long, value_name = "POSES.json")]
    pub poses: Option<String>,
    /// Solve every equation at once instead of group by group (the reference).
    #[arg(long)]
    pub global: bool,
    /// Closure tolerance in file lengths (default 1e-9 x model size).
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Also report the finite mobility at the solved configuration (local dimension of the
    /// solution set against the first-order mobility; toggles and singular poses named).
    #[arg(long)]
    pub finite: bool,
    /// Output format.
    #[arg(long, value_enum, default_value_t = SolveFormat::Table)]
    pub format: SolveFormat,
}

/// Options of `mbsa assemble`.
#[derive(Args, Debug, Clone)]
pub struct AssembleArgs {
    /// Start from these poses (JSON, as `mbsa solve --format json` writes them).
    #[arg(long, value_name = "POSES.json")]
    pub poses: Option<String>,
    /// Closure tolerance in file lengths (default 1e-9 x model size).
    #[arg(long)]
    pub tolerance: Option<f64>,
}

fn input_err(file: &str, e: &dyn std::error::Error) -> Failure {
    Failure::Input(format!("error: {file}: {e}"))
}

/// An analysis failure: the message on standard error, exit code 1.
fn failed(msg: &str) -> Failure {
    let _ = writeln!(std::io::stderr().lock(), "error: {msg}");
    Failure::Check
}

fn solve_failure(file: &str, e: &SolveError) -> Failure {
    solve_failure_hinted(file, e, "")
}

/// [`solve_failure`], a step that cannot be closed or did not converge followed by `hint`.
fn solve_failure_hinted(file: &str, e: &SolveError, hint: &str) -> Failure {
    match e {
        SolveError::NotConverged { .. } => failed(&format!("{e}{hint}")),
        SolveError::Unreachable { .. } => Failure::Input(format!("error: {file}: {e}{hint}")),
        SolveError::Budget(b) => super::budget_failure(b),
        _ => input_err(file, e),
    }
}

fn warn(msg: &str) {
    let _ = writeln!(std::io::stderr().lock(), "warning: {msg}");
}

/// Read poses written by `mbsa solve --format json` (or a bare array of them).
fn read_poses(path: &str, m: &Mechanism, scale: f64) -> Result<Configuration, Failure> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Failure::Input(format!("error: cannot read `{path}`: {e}")))?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| Failure::Input(format!("error: {path}: not JSON: {e}")))?;
    let list = v.get("poses").unwrap_or(&v);
    let items = list.as_array().ok_or_else(|| {
        Failure::Input(format!(
            "error: {path}: expected an array of poses or {{\"poses\": [...]}}"
        ))
    })?;
    let mut c = Configuration::reference(m.bodies.len());
    for (i, item) in items.iter().enumerate() {
        let bad = |what: &str| Failure::Input(format!("error: {path}: pose {}: {what}", i + 1));
        let body = match item.get("body") {
            Some(serde_json::Value::String(s)) => s.clone(),
            Some(serde_json::Value::Number(n)) => n.to_string(),
            _ => return Err(bad("missing `body`")),
        };
        let idx = (0..m.bodies.len())
            .find(|&b| m.body_id(b).to_string() == body)
            .ok_or_else(|| bad(&format!("no body `{body}` in the mechanism")))?;
        let nums = |key: &str, n: usize| -> Result<Vec<f64>, Failure> {
            let a = item
                .get(key)
                .and_then(|x| x.as_array())
                .ok_or_else(|| bad(&format!("missing `{key}`")))?;
            let v: Vec<f64> = a.iter().filter_map(|x| x.as_f64()).collect();
            if v.len() != n || !v.iter().all(|x| x.is_finite()) {
                return Err(bad(&format!("`{key}` needs {n} finite numbers")));
            }
            Ok(v)
        };
        let t = nums("translation", 3)?;
        let q = nums("quaternion", 4)?;
        let quat = nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]);
        if quat.norm() < 1e-12 {
            return Err(bad("`quaternion` is zero"));
        }
        let rot = nalgebra::UnitQuaternion::from_quaternion(quat).to_rotation_matrix();
        if idx != m.frame {
            c.poses[idx] = Pose {
                rotation: rot.into_inner(),
                translation: nalgebra::Vector3::new(t[0], t[1], t[2]) / scale,
            };
        }
    }
    Ok(c)
}

/// The starting configuration: the file's or `--poses`, checked for closure, assembled if
/// asked.
fn start(
    file: &str,
    m: &Mechanism,
    poses: Option<&str>,
    tolerance: Option<f64>,
    assemble: bool,
) -> Result<(Configuration, Option<String>), Failure> {
    if let Some(t) = tolerance
        && !(t.is_finite() && t > 0.0)
    {
        return Err(Failure::Input(format!(
            "error: --tolerance must be a positive length, not {t}"
        )));
    }
    let scale = mbsa::position::residual::model_size(m);
    let c = match poses {
        Some(p) => read_poses(p, m, scale)?,
        None => Configuration::reference(m.bodies.len()),
    };
    let closure =
        mbsa::position::check_closure(m, &c, tolerance).map_err(|e| input_err(file, &e))?;
    if !assemble {
        match closure.status {
            ClosureStatus::Closed => {}
            ClosureStatus::Open => warn(&closure.message().unwrap_or_default()),
            ClosureStatus::Broken => {
                return Err(Failure::Input(format!(
                    "error: {file}: {}",
                    closure.message().unwrap_or_default()
                )));
            }
        }
        return Ok((c, None));
    }
    let (c2, _) =
        mbsa::position::assemble(m, &c, &NewtonOptions::default()).map_err(|e| match e {
            // From the file's own configuration: a start nearer a closed one may reach it.
            SolveError::Unreachable { .. } if poses.is_none() => Failure::Input(format!(
                "error: {file}: {e}\n  help: either the joints cannot all close (a link too \
                 short), or the file's configuration is too far from a closed one for the \
                 projection: give a nearer start with `--poses FILE` (poses as `mbsa solve \
                 --format json` writes them, e.g. your simulator's own assembled pose)"
            )),
            e => solve_failure(file, &e),
        })?;
    let after =
        mbsa::position::check_closure(m, &c2, tolerance).map_err(|e| input_err(file, &e))?;
    let note = format!(
        "assembled by mbsa: largest joint residual {:.3e} before, {:.3e} after",
        closure.max_residual, after.max_residual
    );
    Ok((c2, Some(note)))
}

fn toml_of(m: &Mechanism, c: &Configuration, note: Option<&str>) -> String {
    let moved = mbsa::position::moved_mechanism(m, c);
    let mut s = String::new();
    if let Some(n) = note {
        s.push_str(&format!("# {n}\n"));
    }
    s.push_str(&mbsa::generate::to_toml(&moved));
    s
}

/// A note for `written` giving `given` values to joint `j` of several DOF: which of its DOF
/// they drive (a value meant as a turn of a planar joint would otherwise move its first slide,
/// silently). `None` when every DOF gets a value, or the file drives as many.
fn fewer_values_note(m: &Mechanism, j: usize, given: usize, written: &str) -> Option<String> {
    let joint = &m.joints[j];
    let grade = joint.grade() as usize * joint.pairs() as usize;
    if given >= grade || (joint.driven as usize == given && given > 0) {
        return None;
    }
    let kind = joint.kind;
    let order = match kind.dof_order() {
        Some(o) => format!("{}'s DOF in order: {o}", kind.code()),
        None => format!(
            "{} has no named DOF: a generic combination of its motions",
            kind.code()
        ),
    };
    let drive = match given {
        1 => "the value drives its first".to_string(),
        n => format!("the {n} values drive its first {n}"),
    };
    Some(format!(
        "`{written}`: joint `{}` ({}) has {grade} DOF; {drive} ({order}; docs/format.md)",
        joint.id,
        kind.code()
    ))
}

/// When a step cannot be closed: the joints `--set` drove that the file does not (`original`),
/// each an input added to the file's, which can over-determine a group (a passive knee of a
/// leg whose motor is driven), and how to move one in place of an input. Empty without such
/// joints.
fn added_inputs_hint(original: &Mechanism, sets: &[(usize, Vec<Value>)]) -> String {
    let added: Vec<&str> = sets
        .iter()
        .filter(|(j, _)| original.joints[*j].driven == 0)
        .map(|(j, _)| original.joints[*j].id.as_str())
        .collect();
    if added.is_empty() {
        return String::new();
    }
    let inputs: Vec<&str> = original
        .joints
        .iter()
        .filter(|j| j.driven > 0)
        .map(|j| j.id.as_str())
        .collect();
    format!(
        "\n  help: `--set` drives {} on top of the file's inputs ({}): where those were all \
         the mechanism needs, that is an input too many, which over-determines a group; to move \
         a joint in place of an input, name the inputs with `--inputs`",
        mbsa::words::capped(&added),
        if inputs.is_empty() {
            "none".to_string()
        } else {
            mbsa::words::capped(&inputs)
        }
    )
}

/// A free joint to the frame that neither the file nor `--set` drives (an imported robot's
/// floating base) is held at the file's pose, as `transform` takes it by default; the notes
/// say so: left free, the solve would move the whole robot by whatever its steps chose (the
/// group-by-group and the global solve each differently), since no equation fixes the base.
fn hold_free_bases(m: &mut Mechanism, sets: &mut Vec<(usize, Vec<Value>)>) -> Vec<String> {
    let mut notes = Vec::new();
    // A free body the other joints tie to the frame too (MuJoCo's `connect` to the world) is
    // no floating base: held, it would fight that tie (`analyze` names no base there either).
    let tied = mbsa::mobility::Components::of_joints(
        m,
        (0..m.joints.len()).filter(|&j| !m.free_to_frame(j)),
    );
    let frame = tied.root(m.frame);
    for j in 0..m.joints.len() {
        if !m.free_to_frame(j) || m.joints[j].driven > 0 {
            continue;
        }
        if m.joints[j].bodies.iter().all(|&b| tied.root(b) == frame) {
            continue;
        }
        let grade = m.joints[j].grade();
        m.joints[j].driven = grade;
        let zero = Value {
            number: 0.0,
            radians: None,
        };
        sets.push((j, vec![zero; grade as usize]));
        let id = &m.joints[j].id;
        notes.push(format!(
            "the floating base `{id}` (a free joint to the frame, not driven) is held at the \
             file's pose; `--set {id}=...` with its {grade} values moves it"
        ));
    }
    notes
}

/// Assembled, the inputs that neither `--set` (the first `given` of `sets`) nor the sweep
/// gives hold the values the assembly left them at: the file's own values are those of its
/// open configuration, which the closed loops may not reach (Gepetto's Disney-like leg: "did
/// not converge", where `mbsa assemble` then `mbsa solve` solved it).
fn hold_assembled(
    m: &Mechanism,
    model: &PositionModel,
    config: &mbsa::position::Configuration,
    given: usize,
    swept: Option<usize>,
    sets: &mut Vec<(usize, Vec<Value>)>,
) {
    let at = mbsa::position::joint_values(m, model, config);
    for (j, joint) in m.joints.iter().enumerate() {
        if joint.driven == 0 || Some(j) == swept || sets[..given].iter().any(|(k, _)| *k == j) {
            continue;
        }
        let values: Vec<Value> = at[j]
            .values
            .iter()
            .zip(&at[j].units)
            .take(joint.driven as usize)
            .map(|(&number, &unit)| Value {
                number,
                radians: (unit == "deg").then_some(false),
            })
            .collect();
        sets.retain(|(k, _)| *k != j);
        sets.push((j, values));
    }
}

/// `mbsa assemble`.
pub fn assemble(file: &FileArg, args: &AssembleArgs) -> Result<(), Failure> {
    let m = load(file)?;
    let (c, note) = start(&file.file, &m, args.poses.as_deref(), args.tolerance, true)?;
    emit(&toml_of(&m, &c, note.as_deref()))
}

/// `mbsa solve`.
pub fn solve(file: &FileArg, args: &SolveArgs) -> Result<(), Failure> {
    // With `--inputs` the chosen inputs replace the file's, for the groups and the values
    // alike (and `--format toml` writes them).
    let original = load_with_inputs(file, args.inputs.as_deref())?;
    let name = file.file.as_str();
    let mut m = original.clone();
    let mut sets: Vec<(usize, Vec<Value>)> = Vec::new();
    let mut written: Vec<&str> = Vec::new();
    for s in &args.set {
        let (j, v) = inputs::parse_set(&m, s).map_err(|e| input_err("--set", &e))?;
        // Two values for one joint (by id or by body pair) cannot both hold: refused, not
        // the last silently kept.
        if let Some(k) = sets.iter().position(|(k, _)| *k == j) {
            return Err(Failure::Input(format!(
                "error: --set: joint `{}` is given twice (`{}` and `{s}`)\n  help: give each joint one value; `--sweep` traces a range",
                m.joints[j].id, written[k]
            )));
        }
        if let Some(n) = fewer_values_note(&m, j, v.len(), s) {
            warn(&n);
        }
        sets.push((j, v));
        written.push(s);
    }
    let sweep = match &args.sweep {
        Some(s) => Some(inputs::parse_sweep(&m, s).map_err(|e| input_err("--sweep", &e))?),
        None => None,
    };
    // The sweep sets its joint at every step: a `--set` of it would be dropped.
    if let Some(sw) = &sweep
        && let Some(k) = sets.iter().position(|(k, _)| *k == sw.joint)
    {
        return Err(Failure::Input(format!(
            "error: joint `{}` is given by both `--sweep` and `--set` (`{}`)\n  help: the sweep \
             sets it at every step; drop the `--set`, or start the range there",
            m.joints[sw.joint].id, written[k]
        )));
    }
    if let Some(sw) = &sweep
        && let Some(n) = fewer_values_note(&m, sw.joint, 1, args.sweep.as_deref().unwrap_or(""))
    {
        warn(&n);
    }
    inputs::drive(&mut m, &sets);
    if let Some(sw) = &sweep {
        let j = &mut m.joints[sw.joint];
        j.driven = j.driven.max(1);
    }
    let given = sets.len();
    let held = hold_free_bases(&mut m, &mut sets);
    let model = PositionModel::new(&m).map_err(|e| input_err(name, &e))?;
    held.iter().for_each(|w| warn(w));
    let (config, note) = start(
        name,
        &m,
        args.poses.as_deref(),
        args.tolerance,
        args.assemble,
    )?;
    if args.assemble {
        let swept = sweep.as_ref().map(|s| s.joint);
        hold_assembled(&m, &model, &config, given, swept, &mut sets);
    }
    let opts = NewtonOptions {
        budget: super::budget(),
        ..NewtonOptions::default()
    };
    // The closure was checked (or the configuration assembled) above: the groups come from
    // the first bodies' geometry.
    let mut first = m.clone();
    for j in &mut first.joints {
        j.geometry.second = None;
    }
    let a = structure::analyze(&first, &structure::Options::default(), &Library::builtin())
        .map_err(|e| input_err(name, &e))?;
    let sched = mbsa::position::schedule(&m, &a, &model);
    let method = if args.global { "global" } else { "groups" };
    let Some(sw) = sweep else {
        let tg = inputs::targets(&m, &model, &sets).map_err(|e| input_err("--set", &e))?;
        let sol = if args.global {
            mbsa::position::solve_global(&m, &model, &tg, &config, &opts)
        } else {
            mbsa::position::solve_groups(&m, &model, &sched, &tg, &config, &opts)
        }
        .map_err(|e| {
            solve_failure_hinted(name, &e, &added_inputs_hint(&original, &sets[..given]))
        })?;
        let mut report = SolveReport::new(&m, &model, &sol, method);
        report.isolated = a
            .isolated
            .iter()
            .map(|i| (i.body.clone(), i.dimension))
            .collect();
        if args.finite {
            report.finite = Some(
                mbsa::position::finite_mobility(
                    &m,
                    &sol.config,
                    &mbsa::position::FiniteOptions {
                        budget: super::budget(),
                        ..Default::default()
                    },
                )
                .map_err(|e| match e {
                    SolveError::Budget(b) => super::budget_failure(&b),
                    e => input_err(name, &e),
                })?,
            );
            // As `rigid --finite`: on rounded numbers a disagreement is not decided.
            if let Some(f) = report.finite.as_mut() {
                mbsa::position::caveat_rounded(f, mbsa::motion::written_precision(&m), None);
            }
        }
        return emit(&match args.format {
            SolveFormat::Table => mbsa::report::position::solve_table(&report),
            SolveFormat::Json => mbsa::report::json(&report),
            SolveFormat::Toml => toml_of(&original, &sol.config, note.as_deref()),
        });
    };
    let how = if args.global {
        Method::Global
    } else {
        Method::Groups
    };
    let r = sweep::sweep(&m, &model, &sched, &sets, &sw, config, how, &opts)
        .map_err(|e| input_err("--set", &e))?;
    emit(&match args.format {
        SolveFormat::Json => mbsa::report::json(&r),
        _ => {
            let rows: Vec<_> = r
                .steps
                .iter()
                .map(|s| (s.value, s.joint_values.clone()))
                .collect();
            mbsa::report::position::sweep_table(&r.joint, &rows)
        }
    })?;
    match r.stopped {
        Some(msg) => Err(failed(&msg)),
        None => Ok(()),
    }
}
