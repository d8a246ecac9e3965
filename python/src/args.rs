//! The keyword arguments of `segment`, turned into the core's `Params` as the command line's
//! `ParamArgs::params` turns its flags: the defaults are `Params::default()`'s, the ranges
//! are checked by `Params::validate` (whose messages name the parameter and its range), and
//! the combinations the command line refuses are refused here too.
use bvseg_core::{Kinds, Params, Target};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyString};

/// Most threads, as on the command line.
const MAX_THREADS: u64 = 4096;
/// Longest timeout in seconds (about a year), as on the command line.
const MAX_TIMEOUT: f64 = 3.2e7;

/// The keyword arguments as given (`None`: not given).
#[derive(Default)]
pub struct Given<'py> {
    pub k: Option<Bound<'py, PyAny>>,
    pub tov: Option<f64>,
    pub max_protrusion: Option<f64>,
    pub max_protrusion_abs: Option<f64>,
    pub mov: Option<f64>,
    pub max_k: Option<Bound<'py, PyAny>>,
    pub kinds: Option<Bound<'py, PyAny>>,
    pub target: Option<String>,
    pub max_hull_vertices: Option<Bound<'py, PyAny>>,
    pub samples: Option<Bound<'py, PyAny>>,
    pub seed: Option<Bound<'py, PyAny>>,
    pub merge: bool,
    pub tighten: bool,
    pub hierarchy: bool,
    pub margin: Option<f64>,
    pub threads: Option<Bound<'py, PyAny>>,
    pub timeout: Option<f64>,
    pub skeleton: Option<String>,
    pub sampling: Option<String>,
    pub route: Option<String>,
    pub per_bone: Option<Bound<'py, PyAny>>,
}

/// What a run needs besides the mesh.
pub struct RunArgs {
    pub params: Params,
    pub threads: Option<usize>,
    pub timeout: Option<f64>,
}

/// A non-negative integer argument: `TypeError` for a non-integer (bools included),
/// `ValueError` naming the parameter for a negative one.
pub fn uint(name: &str, v: &Bound<'_, PyAny>) -> PyResult<u64> {
    if v.is_instance_of::<PyBool>() {
        return Err(PyTypeError::new_err(format!(
            "{name} must be an integer, got a bool"
        )));
    }
    if let Ok(x) = v.extract::<u64>() {
        return Ok(x);
    }
    match v.extract::<i128>() {
        Ok(x) if x < 0 => Err(PyValueError::new_err(format!(
            "{name} must be a non-negative integer, got {x}"
        ))),
        Ok(x) => Err(PyValueError::new_err(format!(
            "{name} is too large, got {x}"
        ))),
        Err(_) => Err(PyTypeError::new_err(format!(
            "{name} must be an integer, got {}",
            type_name(v)
        ))),
    }
}

fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "an object".into())
}

pub fn size(name: &str, v: &Bound<'_, PyAny>) -> PyResult<usize> {
    // Above usize::MAX (32-bit platforms) the core's range check says so.
    Ok(usize::try_from(uint(name, v)?).unwrap_or(usize::MAX))
}

/// A `kinds` argument: a comma list as `--bv` takes it (`"obb,capsule"`, `"mixed"`, `"all"`),
/// or a list of such names.
fn kinds(v: &Bound<'_, PyAny>) -> PyResult<Kinds> {
    let text = if let Ok(s) = v.cast::<PyString>() {
        s.to_str()?.to_owned()
    } else if v.is_instance_of::<PyList>() || v.is_instance_of::<pyo3::types::PyTuple>() {
        let mut names = Vec::new();
        for item in v.try_iter()? {
            let item = item?;
            let s = item.cast::<PyString>().map_err(|_| {
                PyTypeError::new_err(format!(
                    "kinds must be a string or a list of strings, got a list with {}",
                    type_name(&item)
                ))
            })?;
            names.push(s.to_str()?.to_owned());
        }
        names.join(",")
    } else {
        return Err(PyTypeError::new_err(format!(
            "kinds must be a string or a list of strings, got {}",
            type_name(v)
        )));
    };
    text.parse::<Kinds>()
        .map_err(|e| PyValueError::new_err(format!("kinds: {e}")))
}

/// A `target` name, as `--target` takes it.
fn target(name: &str) -> PyResult<Kinds> {
    Target::kinds_of(name).ok_or_else(|| {
        let names: Vec<&str> = Target::ALL.iter().map(|t| t.as_str()).collect();
        PyValueError::new_err(format!(
            "target: unknown target {name:?}: expected one of {} (or rapier, avian, isaac), \
             optionally with -hull",
            names.join(", ")
        ))
    })
}

/// The keyword arguments `segment` takes besides the mesh and `progress`.
pub const NAMES: [&str; 21] = [
    "k",
    "tov",
    "max_protrusion",
    "max_protrusion_abs",
    "mov",
    "max_k",
    "kinds",
    "target",
    "max_hull_vertices",
    "samples",
    "seed",
    "threads",
    "merge",
    "tighten",
    "hierarchy",
    "margin",
    "timeout",
    "skeleton",
    "sampling",
    "route",
    "per_bone",
];

/// A float argument (an int is taken too): `TypeError` naming the parameter otherwise.
fn float(name: &str, v: &Bound<'_, PyAny>) -> PyResult<f64> {
    if v.is_instance_of::<PyBool>() {
        return Err(PyTypeError::new_err(format!(
            "{name} must be a number, got a bool"
        )));
    }
    v.extract::<f64>()
        .map_err(|_| PyTypeError::new_err(format!("{name} must be a number, got {}", type_name(v))))
}

fn string(name: &str, v: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(v.cast::<PyString>()
        .map_err(|_| {
            PyTypeError::new_err(format!("{name} must be a string, got {}", type_name(v)))
        })?
        .to_str()?
        .to_owned())
}

fn boolean(name: &str, v: &Bound<'_, PyAny>) -> PyResult<bool> {
    v.extract::<bool>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name} must be True or False, got {}",
            type_name(v)
        ))
    })
}

impl<'py> Given<'py> {
    /// The keyword arguments of `function` (for messages) from `kwargs`; a value of `None`
    /// is the default. `TypeError` for an unknown keyword or a value of the wrong type.
    pub fn from_kwargs(function: &str, kwargs: Option<&Bound<'py, PyDict>>) -> PyResult<Self> {
        let mut g = Given {
            merge: true,
            tighten: true,
            hierarchy: true,
            ..Given::default()
        };
        let Some(kwargs) = kwargs else {
            return Ok(g);
        };
        for (key, value) in kwargs.iter() {
            let key: String = key.extract()?;
            if value.is_none() {
                // `polish` is the former name of `tighten`.
                if !NAMES.contains(&key.as_str()) && key != "polish" {
                    return Err(unknown(function, &key));
                }
                continue;
            }
            let v = Some(value.clone());
            match key.as_str() {
                "k" => g.k = v,
                "tov" => g.tov = Some(float(&key, &value)?),
                "max_protrusion" => g.max_protrusion = Some(float(&key, &value)?),
                "max_protrusion_abs" => g.max_protrusion_abs = Some(float(&key, &value)?),
                "mov" => g.mov = Some(float(&key, &value)?),
                "max_k" => g.max_k = v,
                "kinds" => g.kinds = v,
                "target" => {
                    g.target = Some(
                        value
                            .cast::<PyString>()
                            .map_err(|_| {
                                PyTypeError::new_err(format!(
                                    "target must be a string, got {}",
                                    type_name(&value)
                                ))
                            })?
                            .to_str()?
                            .to_owned(),
                    )
                }
                "max_hull_vertices" => g.max_hull_vertices = v,
                "samples" => g.samples = v,
                "seed" => g.seed = v,
                "threads" => g.threads = v,
                "merge" => g.merge = boolean(&key, &value)?,
                // `polish` is the former name of `tighten`.
                "tighten" | "polish" => g.tighten = boolean(&key, &value)?,
                "hierarchy" => g.hierarchy = boolean(&key, &value)?,
                "margin" => g.margin = Some(float(&key, &value)?),
                "timeout" => g.timeout = Some(float(&key, &value)?),
                "skeleton" => g.skeleton = Some(string(&key, &value)?),
                "sampling" => g.sampling = Some(string(&key, &value)?),
                "route" => g.route = Some(string(&key, &value)?),
                "per_bone" => g.per_bone = v,
                _ => return Err(unknown(function, &key)),
            }
        }
        Ok(g)
    }

    /// The validated parameters, threads and timeout.
    pub fn resolve(&self) -> PyResult<RunArgs> {
        let conflict = |a: &str, b: &str, why: &str| {
            PyValueError::new_err(format!("{a} and {b} cannot be combined: {why}"))
        };
        if self.k.is_some() {
            let tolerances = [
                ("tov", self.tov.is_some()),
                ("mov", self.mov.is_some()),
                ("max_protrusion", self.max_protrusion.is_some()),
                ("max_protrusion_abs", self.max_protrusion_abs.is_some()),
            ];
            if let Some((name, _)) = tolerances.iter().find(|t| t.1) {
                return Err(conflict(
                    "k",
                    name,
                    "a fixed number of parts has no tolerances",
                ));
            }
        }
        if self.max_protrusion.is_some() && self.max_protrusion_abs.is_some() {
            return Err(conflict(
                "max_protrusion",
                "max_protrusion_abs",
                "give the tolerance on the protrusion either relative or absolute",
            ));
        }
        let d = Params::default();
        let kinds = match (&self.kinds, &self.target) {
            (Some(_), Some(_)) => {
                return Err(conflict(
                    "kinds",
                    "target",
                    "a target names its own set of kinds",
                ))
            }
            (Some(k), None) => kinds(k)?,
            (None, Some(t)) => target(t)?,
            (None, None) => d.kinds,
        };
        let opt_size = |name: &str, v: &Option<Bound<'_, PyAny>>| -> PyResult<Option<usize>> {
            v.as_ref().map(|v| size(name, v)).transpose()
        };
        let params = Params {
            samples: opt_size("samples", &self.samples)?.unwrap_or(d.samples),
            seed: self
                .seed
                .as_ref()
                .map(|v| uint("seed", v))
                .transpose()?
                .unwrap_or(d.seed),
            kinds,
            max_hull_vertices: opt_size("max_hull_vertices", &self.max_hull_vertices)?
                .unwrap_or(d.max_hull_vertices),
            k: opt_size("k", &self.k)?,
            tov: self.tov.unwrap_or(d.tov),
            mov: self.mov,
            max_protrusion: self.max_protrusion.unwrap_or(d.max_protrusion),
            max_protrusion_abs: self.max_protrusion_abs,
            max_k: opt_size("max_k", &self.max_k)?.unwrap_or(d.max_k),
            merge: self.merge,
            tighten: self.tighten,
            hierarchy: self.hierarchy,
            margin: self.margin.unwrap_or(d.margin),
            skeleton: match &self.skeleton {
                Some(s) => s
                    .parse()
                    .map_err(|e| PyValueError::new_err(format!("skeleton: {e}")))?,
                None => d.skeleton,
            },
            sampling: match &self.sampling {
                Some(s) => s
                    .parse()
                    .map_err(|e| PyValueError::new_err(format!("sampling: {e}")))?,
                None => d.sampling,
            },
            route: match &self.route {
                Some(s) => s
                    .parse()
                    .map_err(|e| PyValueError::new_err(format!("route: {e}")))?,
                None => d.route,
            },
            per_bone: opt_size("per_bone", &self.per_bone)?,
            ..d
        };
        params
            .validate()
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let threads = match &self.threads {
            None => None,
            Some(v) => {
                let t = uint("threads", v)?;
                if !(1..=MAX_THREADS).contains(&t) {
                    return Err(PyValueError::new_err(format!(
                        "threads must be between 1 and {MAX_THREADS}, got {t}"
                    )));
                }
                // At most 4096: fits.
                Some(t as usize)
            }
        };
        if let Some(t) = self.timeout {
            if !(t > 0.0 && t <= MAX_TIMEOUT) {
                return Err(PyValueError::new_err(format!(
                    "timeout must be a number of seconds above 0 (and at most a year), got {t}"
                )));
            }
        }
        Ok(RunArgs {
            params,
            threads,
            timeout: self.timeout,
        })
    }
}

fn unknown(function: &str, key: &str) -> PyErr {
    let own = if function == "robot" {
        "source, max_parts, total_parts, spheres_per_link, urdf_capsules, progress, "
    } else {
        ""
    };
    PyTypeError::new_err(format!(
        "{function}() got an unexpected keyword argument '{key}' (it takes {own}{})",
        NAMES.join(", ")
    ))
}

/// Checks `segment`'s keyword arguments without running anything: the errors `segment`
/// would raise for them.
#[pyfunction]
#[pyo3(signature = (**params))]
pub fn check_params(params: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
    Given::from_kwargs("segment", params)?.resolve().map(|_| ())
}

/// The defaults of `segment`'s keyword arguments: `Params::default()`'s (`None` where the
/// parameter is off by default), with `kinds` as its comma list.
#[pyfunction]
pub fn defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = Params::default();
    let out = PyDict::new(py);
    out.set_item("k", d.k)?;
    out.set_item("tov", d.tov)?;
    out.set_item("max_protrusion", d.max_protrusion)?;
    out.set_item("max_protrusion_abs", d.max_protrusion_abs)?;
    out.set_item("mov", d.mov)?;
    out.set_item("max_k", d.max_k)?;
    out.set_item("kinds", d.kinds.to_string())?;
    out.set_item("target", py.None())?;
    out.set_item("max_hull_vertices", d.max_hull_vertices)?;
    out.set_item("samples", d.samples)?;
    out.set_item("seed", d.seed)?;
    out.set_item("threads", py.None())?;
    out.set_item("merge", d.merge)?;
    out.set_item("tighten", d.tighten)?;
    out.set_item("hierarchy", d.hierarchy)?;
    out.set_item("margin", d.margin)?;
    out.set_item("timeout", py.None())?;
    out.set_item("skeleton", d.skeleton.to_string())?;
    out.set_item("sampling", d.sampling.to_string())?;
    out.set_item("route", d.route.to_string())?;
    out.set_item("per_bone", d.per_bone)?;
    Ok(out)
}

/// The names `target` takes (each also with `-hull`; also rapier, avian, isaac).
#[pyfunction]
pub fn targets() -> Vec<&'static str> {
    Target::ALL.iter().map(|t| t.as_str()).collect()
}
