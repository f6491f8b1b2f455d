//! The mechanism object and its analyses, each the call its command makes (src/cli/).

use crate::errors;
use mbsa::Mechanism;
use mbsa::budget::Budget;
use mbsa::geometry::GeometrySource;
use mbsa::position::inputs::{self, Value};
use mbsa::position::{self, ClosureStatus, Configuration, NewtonOptions, PositionModel};
use mbsa::rigidity::both as rigid;
use mbsa::structure::{self, Library, Method};
use mbsa::transform::{self, BaseMode, Criterion, TransformOptions};
use pyo3::prelude::*;

/// A mechanism read by `load` (the package wraps it in `mbsa.Mechanism`).
#[pyclass(module = "mbsa._mbsa", frozen)]
pub struct RawMechanism {
    m: Mechanism,
    source: String,
}

impl RawMechanism {
    pub fn new(m: Mechanism, source: String) -> Self {
        RawMechanism { m, source }
    }

    /// The mechanism with an `inputs` spec applied (`--inputs`).
    fn with_inputs(&self, spec: Option<&str>) -> PyResult<Mechanism> {
        let mut m = self.m.clone();
        if let Some(spec) = spec {
            mbsa::InputSpec::parse_in(spec, &m)
                .and_then(|s| m.apply_inputs(&s))
                .map_err(|e| errors::plain("inputs", &e))?;
        }
        Ok(m)
    }

    /// The closure check of the file's configuration before an analysis at `source`: an
    /// error when a joint's `second` geometry misses closure grossly (as the command line).
    fn closure_check(
        &self,
        m: &Mechanism,
        source: GeometrySource,
        precision: Option<f64>,
    ) -> PyResult<()> {
        if !m.joints.iter().any(|j| j.geometry.second.is_some()) {
            return Ok(());
        }
        match mbsa::geometry::choose(m, source, precision) {
            Err(e @ mbsa::motion::MotionError::NotClosed { .. }) => {
                Err(errors::plain(&self.source, &e))
            }
            _ => Ok(()),
        }
    }
}

fn budget(max_work: Option<u64>) -> Budget {
    let mut b = Budget::DEFAULT;
    if let Some(w) = max_work {
        b.max_work = w;
    }
    b
}

fn geometry(kind: &str, seed: u64) -> PyResult<GeometrySource> {
    match kind {
        "auto" => Ok(GeometrySource::Auto { seed }),
        "file" => Ok(GeometrySource::File),
        "random" => Ok(GeometrySource::Random { seed }),
        _ => Err(bad(
            "geometry",
            &format!("`{kind}` is not auto, file or random"),
        )),
    }
}

fn bad(what: &str, msg: &str) -> PyErr {
    errors::input_error(
        Some(what),
        None,
        None,
        msg,
        None,
        format!("error: {what}: {msg}\n"),
    )
}

fn precision(tolerance: Option<f64>) -> PyResult<Option<f64>> {
    match tolerance {
        Some(t) if !(t.is_finite() && t >= 0.0) => {
            Err(bad("tolerance", "must be a finite number >= 0"))
        }
        t => Ok(t),
    }
}

fn solve_error(file: &str, e: &position::SolveError) -> PyErr {
    match e {
        position::SolveError::NotConverged { .. } => errors::SolveError::new_err(e.to_string()),
        position::SolveError::Budget(b) => errors::budget(b),
        _ => errors::plain(file, e),
    }
}

#[pymethods]
impl RawMechanism {
    /// The mechanism's name.
    #[getter]
    fn name(&self) -> String {
        self.m.name.clone()
    }

    /// Where it was read from, as errors name it.
    #[getter]
    fn source(&self) -> String {
        self.source.clone()
    }

    /// Body ids, in the mechanism's order (the frame first).
    #[getter]
    fn bodies(&self) -> Vec<String> {
        (0..self.m.bodies.len())
            .map(|b| self.m.body_id(b).to_string())
            .collect()
    }

    /// Joint ids, in the mechanism's order.
    #[getter]
    fn joints(&self) -> Vec<String> {
        self.m.joints.iter().map(|j| j.id.clone()).collect()
    }

    /// `mbsa mobility --format json`.
    #[pyo3(signature = (inputs=None))]
    fn mobility_json(&self, py: Python<'_>, inputs: Option<&str>) -> PyResult<String> {
        let m = self.with_inputs(inputs)?;
        Ok(py.detach(|| mbsa::report::json(&mbsa::mobility::mobility(&m))))
    }

    /// `mbsa analyze --format json`.
    #[pyo3(signature = (inputs=None, geometry="auto", seed=0, tolerance=None, count_only=false, exhaustive=false, max_work=None))]
    #[allow(clippy::too_many_arguments)]
    fn analyze_json(
        &self,
        py: Python<'_>,
        inputs: Option<&str>,
        geometry: &str,
        seed: u64,
        tolerance: Option<f64>,
        count_only: bool,
        exhaustive: bool,
        max_work: Option<u64>,
    ) -> PyResult<String> {
        let m = self.with_inputs(inputs)?;
        let opts = structure::Options {
            count_only,
            method: if exhaustive {
                Method::Exhaustive
            } else {
                Method::Flow
            },
            geometry: self::geometry(geometry, seed)?,
            precision: precision(tolerance)?,
        };
        if !count_only {
            self.closure_check(&m, opts.geometry, opts.precision)?;
        }
        let b = budget(max_work);
        py.detach(|| {
            let mut a = structure::analyze_within(&m, &opts, &Library::builtin(), &b).map_err(
                |e| match e {
                    structure::AnalyzeError::Motion(e) => errors::plain(&self.source, &e),
                    structure::AnalyzeError::Budget(e) => errors::budget(&e),
                },
            )?;
            structure::check_finite(&m, &mut a, opts.precision, b.max_work);
            Ok(mbsa::report::json(&a))
        })
    }

    /// `mbsa rigid --format json`.
    #[pyo3(signature = (method="both", finite=false, with_inputs=false, geometry="auto", seed=0, tolerance=None, inputs=None, max_work=None))]
    #[allow(clippy::too_many_arguments)]
    fn rigid_json(
        &self,
        py: Python<'_>,
        method: &str,
        finite: bool,
        with_inputs: bool,
        geometry: &str,
        seed: u64,
        tolerance: Option<f64>,
        inputs: Option<&str>,
        max_work: Option<u64>,
    ) -> PyResult<String> {
        let m = self.with_inputs(inputs)?;
        let methods = match method {
            "both" => rigid::Methods::Both,
            "counting" => rigid::Methods::Counting,
            "geometric" => rigid::Methods::Geometric,
            _ => {
                return Err(bad(
                    "method",
                    &format!("`{method}` is not both, counting or geometric"),
                ));
            }
        };
        let opts = rigid::RigidOptions {
            methods,
            with_inputs,
            finite,
            geometry: self::geometry(geometry, seed)?,
            precision: precision(tolerance)?,
            budget: budget(max_work),
        };
        if methods != rigid::Methods::Counting || finite {
            self.closure_check(&m, opts.geometry, opts.precision)?;
        }
        py.detach(|| {
            let r = rigid::analyze(&m, &opts).map_err(|e| match e {
                rigid::RigidError::Budget(b) => errors::budget(&b),
                e => errors::plain(&self.source, &e),
            })?;
            Ok(mbsa::report::rigid::json(&r))
        })
    }

    /// `mbsa transform --format jsonl`: the placements' lines and the summary line.
    #[pyo3(signature = (limit=None, rank=None, on=None, grounded=false, keep=None, exclude=None, max_expansions=64, count_only=false, max_work=None, base="auto"))]
    #[allow(clippy::too_many_arguments)]
    fn transform_jsonl(
        &self,
        py: Python<'_>,
        limit: Option<usize>,
        rank: Option<&str>,
        on: Option<&str>,
        grounded: bool,
        keep: Option<&str>,
        exclude: Option<&str>,
        max_expansions: usize,
        count_only: bool,
        max_work: Option<u64>,
        base: &str,
    ) -> PyResult<(Vec<String>, String)> {
        // `--fix-base` and `--keep-free-base` of the CLI.
        let base = match base {
            "auto" => BaseMode::Auto,
            "fixed" => BaseMode::Fixed,
            "free" => BaseMode::Free,
            other => {
                let msg = format!("must be \"auto\", \"fixed\" or \"free\", not {other:?}");
                return Err(errors::input_error(
                    Some("base"),
                    None,
                    None,
                    &msg,
                    None,
                    format!("base: {msg}"),
                ));
            }
        };
        let m = &self.m;
        let spec = |t: Option<&str>, what: &str| {
            t.map(|t| mbsa::InputSpec::parse_in(t, m))
                .transpose()
                .map_err(|e| errors::plain(what, &e))
        };
        let opts = TransformOptions {
            rank: match rank {
                Some(r) => Criterion::parse_list(r).map_err(|e| errors::plain("rank", &e))?,
                None => Criterion::DEFAULT.to_vec(),
            },
            on: on
                .map(TransformOptions::parse_on)
                .transpose()
                .map_err(|e| errors::plain("on", &e))?,
            grounded,
            keep: spec(keep, "keep")?,
            exclude: spec(exclude, "exclude")?,
            max_expansions,
            limit,
            budget: budget(max_work),
            analysis: structure::Options {
                count_only,
                ..Default::default()
            },
            base,
            ..TransformOptions::default()
        };
        if !count_only {
            self.closure_check(m, opts.analysis.geometry, None)?;
        }
        py.detach(|| {
            let mut lines = Vec::new();
            let summary = transform::enumerate(m, &opts, &Library::builtin(), None, &mut |p| {
                lines.push(mbsa::report::json::jsonl(&p));
            })
            .map_err(|e| match e {
                transform::TransformError::Budget(b) => errors::budget(&b),
                e => errors::plain("transform", &e),
            })?;
            Ok((lines, mbsa::report::json::jsonl(&summary)))
        })
    }

    /// `mbsa solve --set ... --format json`.
    #[pyo3(signature = (sets, inputs=None, max_work=None))]
    fn solve_json(
        &self,
        py: Python<'_>,
        sets: Vec<String>,
        inputs: Option<&str>,
        max_work: Option<u64>,
    ) -> PyResult<String> {
        let (m, sets, model, config, sched) = self.position(inputs, &sets, None)?;
        let opts = NewtonOptions {
            budget: budget(max_work),
            ..NewtonOptions::default()
        };
        py.detach(|| {
            let tg = inputs::targets(&m, &model, &sets).map_err(|e| errors::plain("set", &e))?;
            let sol = position::solve_groups(&m, &model, &sched, &tg, &config, &opts)
                .map_err(|e| solve_error(&self.source, &e))?;
            Ok(mbsa::report::json(&position::SolveReport::new(
                &m, &model, &sol, "groups",
            )))
        })
    }

    /// `mbsa solve --sweep JOINT=FROM..TO:STEP --format json`.
    #[pyo3(signature = (sweep, sets, inputs=None, max_work=None))]
    fn sweep_json(
        &self,
        py: Python<'_>,
        sweep: &str,
        sets: Vec<String>,
        inputs: Option<&str>,
        max_work: Option<u64>,
    ) -> PyResult<String> {
        let (m, sets, model, config, sched) = self.position(inputs, &sets, Some(sweep))?;
        let sw = inputs::parse_sweep(&m, sweep).map_err(|e| errors::plain("sweep", &e))?;
        let opts = NewtonOptions {
            budget: budget(max_work),
            ..NewtonOptions::default()
        };
        py.detach(|| {
            let r = position::sweep::sweep(
                &m,
                &model,
                &sched,
                &sets,
                &sw,
                config,
                position::sweep::Method::Groups,
                &opts,
            )
            .map_err(|e| errors::plain("sweep", &e))?;
            Ok(mbsa::report::json(&r))
        })
    }

    /// `mbsa dot --view VIEW`: Graphviz DOT of `diagram`, `structure` or `topology`.
    #[pyo3(signature = (view="diagram", inputs=None))]
    fn dot(&self, py: Python<'_>, view: &str, inputs: Option<&str>) -> PyResult<String> {
        use mbsa::report::dot::View;
        let view = match view {
            "diagram" => View::Diagram,
            "structure" => View::Structure,
            "topology" => View::Topology,
            _ => {
                return Err(bad(
                    "view",
                    &format!("`{view}` is not diagram, structure or topology"),
                ));
            }
        };
        let m = self.with_inputs(inputs)?;
        let opts = structure::Options::default();
        self.closure_check(&m, opts.geometry, None)?;
        py.detach(|| {
            let a = structure::analyze_within(&m, &opts, &Library::builtin(), &Budget::DEFAULT)
                .map_err(|e| match e {
                    structure::AnalyzeError::Motion(e) => errors::plain(&self.source, &e),
                    structure::AnalyzeError::Budget(e) => errors::budget(&e),
                })?;
            Ok(mbsa::report::dot::render(view, &m, &a))
        })
    }

    /// `mbsa repair --format json`: the checked candidates.
    #[pyo3(signature = (candidates=4, max_work=None))]
    fn repair_json(
        &self,
        py: Python<'_>,
        candidates: usize,
        max_work: Option<u64>,
    ) -> PyResult<String> {
        let r = self.repair(py, candidates, max_work)?;
        Ok(mbsa::report::repair::json(&r))
    }

    /// `mbsa repair --apply N --format toml`: the model repaired by candidate `n` (1-based).
    #[pyo3(signature = (n=1, candidates=4, max_work=None))]
    fn repaired_toml(
        &self,
        py: Python<'_>,
        n: usize,
        candidates: usize,
        max_work: Option<u64>,
    ) -> PyResult<String> {
        let r = self.repair(py, candidates, max_work)?;
        let Some(c) = n.checked_sub(1).and_then(|i| r.candidates.get(i)) else {
            return Err(bad(
                "candidate",
                &format!("{n}: {} candidate(s) listed", r.candidates.len()),
            ));
        };
        let repaired = mbsa::repair::apply(&self.m, c);
        let comments: Vec<Option<String>> = repaired
            .joints
            .iter()
            .map(|j| {
                let change = c.changes.iter().find(|ch| ch.joint == j.id);
                change.map(mbsa::report::repair::comment)
            })
            .collect();
        Ok(mbsa::write::write(
            &repaired,
            mbsa::write::TextFormat::Toml,
            &comments,
        ))
    }

    /// The mechanism as a format-v1 TOML file.
    fn to_toml(&self) -> String {
        mbsa::generate::to_toml(&self.m)
    }
}

impl RawMechanism {
    /// The repair of `mbsa repair`, with the interpreter released.
    fn repair(
        &self,
        py: Python<'_>,
        candidates: usize,
        max_work: Option<u64>,
    ) -> PyResult<mbsa::repair::RepairReport> {
        let opts = mbsa::repair::RepairOptions {
            candidates: candidates.clamp(1, 64),
            budget: budget(max_work),
        };
        py.detach(|| {
            mbsa::repair::repair(&self.m, &opts).map_err(|e| match e {
                mbsa::repair::RepairError::Budget(b) => errors::budget(&b),
                e => errors::plain(&self.source, &e),
            })
        })
    }
}

type Prepared = (
    Mechanism,
    Vec<(usize, Vec<Value>)>,
    PositionModel,
    Configuration,
    position::Schedule,
);

impl RawMechanism {
    /// What `mbsa solve` prepares: the values set (their joints driven), the position model,
    /// the file's configuration checked for closure, the solve schedule of the groups.
    fn position(
        &self,
        inputs: Option<&str>,
        set: &[String],
        sweep: Option<&str>,
    ) -> PyResult<Prepared> {
        let mut m = self.with_inputs(inputs)?;
        let mut sets: Vec<(usize, Vec<Value>)> = Vec::new();
        for s in set {
            let (j, v) = inputs::parse_set(&m, s).map_err(|e| errors::plain("set", &e))?;
            if sets.iter().any(|(k, _)| *k == j) {
                return Err(bad(
                    "set",
                    &format!("joint `{}` is given twice", m.joints[j].id),
                ));
            }
            sets.push((j, v));
        }
        inputs::drive(&mut m, &sets);
        if let Some(text) = sweep {
            let sw = inputs::parse_sweep(&m, text).map_err(|e| errors::plain("sweep", &e))?;
            let j = &mut m.joints[sw.joint];
            j.driven = j.driven.max(1);
        }
        let model = PositionModel::new(&m).map_err(|e| errors::plain(&self.source, &e))?;
        let config = Configuration::reference(m.bodies.len());
        let closure = position::check_closure(&m, &config, None)
            .map_err(|e| errors::plain(&self.source, &e))?;
        if closure.status == ClosureStatus::Broken {
            let msg = closure.message().unwrap_or_default();
            return Err(bad(&self.source, &msg));
        }
        // The groups come from the first bodies' geometry (as `mbsa solve`).
        let mut first = m.clone();
        for j in &mut first.joints {
            j.geometry.second = None;
        }
        let a = structure::analyze(&first, &structure::Options::default(), &Library::builtin())
            .map_err(|e| errors::plain(&self.source, &e))?;
        let sched = position::schedule(&m, &a, &model);
        Ok((m, sets, model, config, sched))
    }
}
