//! The stages' options from the keyword arguments Python passes: each name the stage's option
//! (the command line's flag with `_` for `-`), each value checked for its type here and for its
//! range by the stage (whose messages name it `name=`).

use glam::{DVec2, DVec3};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use lamina::rationalize::planarize::Selector;
use lamina::stage;

/// The keyword arguments of one call, taken one by one; what is left is an error.
pub struct Opts<'a, 'py> {
    d: &'a Bound<'py, PyDict>,
    function: &'static str,
}

impl<'a, 'py> Opts<'a, 'py> {
    pub fn new(d: &'a Bound<'py, PyDict>, function: &'static str) -> Self {
        Opts { d, function }
    }

    fn take(&mut self, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let v = self.d.get_item(key)?;
        if v.is_some() {
            self.d.del_item(key)?;
        }
        Ok(v.filter(|v| !v.is_none()))
    }

    /// The value under `key` when it is a string, taken; anything else is left for a typed
    /// read (`fit=` is the longest side in mm, or a word for `print`).
    pub fn word(&mut self, key: &str) -> PyResult<Option<String>> {
        let Some(v) = self.d.get_item(key)? else {
            return Ok(None);
        };
        if !v.is_instance_of::<pyo3::types::PyString>() {
            return Ok(None);
        }
        self.d.del_item(key)?;
        Ok(Some(v.extract::<String>()?))
    }

    fn typed<T>(
        &mut self,
        key: &str,
        kind: &str,
        f: impl FnOnce(&Bound<'py, PyAny>) -> PyResult<T>,
    ) -> PyResult<Option<T>> {
        match self.take(key)? {
            None => Ok(None),
            Some(v) => f(&v).map(Some).map_err(|_| {
                crate::error(format!(
                    "{key}= must be {kind}, got {}",
                    v.repr().map_or_else(|_| "?".into(), |r| r.to_string())
                ))
            }),
        }
    }

    pub fn f64(&mut self, key: &str) -> PyResult<Option<f64>> {
        self.typed(key, "a number", |v| {
            if v.is_instance_of::<pyo3::types::PyBool>() {
                return Err(PyTypeError::new_err("a bool"));
            }
            v.extract::<f64>()
        })
    }

    pub fn usize(&mut self, key: &str) -> PyResult<Option<usize>> {
        self.typed(key, "a whole number ≥ 0", |v| v.extract::<usize>())
    }

    pub fn u32(&mut self, key: &str) -> PyResult<Option<u32>> {
        self.typed(key, "a whole number ≥ 0 (below 2³²)", |v| {
            v.extract::<u32>()
        })
    }

    pub fn u64(&mut self, key: &str) -> PyResult<Option<u64>> {
        self.typed(key, "a whole number ≥ 0", |v| v.extract::<u64>())
    }

    pub fn bool(&mut self, key: &str) -> PyResult<bool> {
        Ok(self
            .typed(key, "True or False", |v| v.extract::<bool>())?
            .unwrap_or(false))
    }

    pub fn string(&mut self, key: &str) -> PyResult<Option<String>> {
        self.typed(key, "a string", |v| v.extract::<String>())
    }

    /// One string or a list of them.
    pub fn strings(&mut self, key: &str) -> PyResult<Vec<String>> {
        Ok(self
            .typed(key, "a string or a list of strings", |v| {
                v.extract::<String>()
                    .map(|s| vec![s])
                    .or_else(|_| v.extract::<Vec<String>>())
            })?
            .unwrap_or_default())
    }

    pub fn f64s(&mut self, key: &str) -> PyResult<Option<Vec<f64>>> {
        self.typed(key, "a list of numbers", |v| v.extract::<Vec<f64>>())
    }

    /// A point or vector of `n` numbers.
    pub fn vector<const N: usize>(&mut self, key: &str) -> PyResult<Option<[f64; N]>> {
        self.typed(key, &format!("{N} numbers"), |v| v.extract::<[f64; N]>())
    }

    /// A value the stage parses from text (the command line's form: `L/500`, `z<1`), with
    /// the parser's message after the option's name.
    pub fn parsed<T>(
        &mut self,
        key: &str,
        parse: impl Fn(&str) -> Result<T, String>,
    ) -> PyResult<Option<T>> {
        match self.string(key)? {
            None => Ok(None),
            Some(s) => parse(&s)
                .map(Some)
                .map_err(|e| crate::error(format!("{key}= {e}"))),
        }
    }

    /// Nothing may be left: an unknown option is a TypeError (the Python side has checked the
    /// names already; this is the last guard).
    pub fn finish(self) -> PyResult<()> {
        if let Some((k, _)) = self.d.iter().next() {
            return Err(PyTypeError::new_err(format!(
                "{}() got an unexpected keyword argument {}",
                self.function,
                k.repr()?
            )));
        }
        Ok(())
    }
}

/// The options each function takes, for the Python side's check of keyword arguments.
pub fn names(function: &str) -> &'static [&'static str] {
    match function {
        "venation" | "venation_on_surface" => &[
            "mode",
            "step",
            "kill",
            "birth",
            "density",
            "birth_min",
            "birth_max",
            "sources",
            "placement",
            "sources_per_step",
            "blade",
            "initial_scale",
            "blade_rate",
            "r",
            "join_distance",
            "join_angle",
            "min_joint_angle",
            "min_member",
            "murray",
            "tip_radius",
            "max_iterations",
            "seed",
            "density_channel",
            "reach",
            "edge_tolerance",
            "root",
        ],
        "veins" => &[
            "source",
            "sources",
            "density_channel",
            "root",
            "tip_radius",
            "murray",
            "smooth",
            "seed",
        ],
        "lsystem" => &[
            "axiom",
            "rule",
            "iterations",
            "angle",
            "step",
            "length_scale",
            "no_simplify",
            "radius",
            "radius_scale",
            "decay",
            "seed",
            "max_symbols",
            "murray",
            "tip_radius",
            "boundary",
            "root_at",
            "fit",
            "no_frame",
            "frame_radius",
            "upright",
            "onto",
            "direction",
            "sag",
        ],
        "bifurcate" => &[
            "depth",
            "length",
            "angle",
            "scale",
            "radius",
            "radius_scale",
            "roll",
            "seed",
            "murray",
            "tip_radius",
            "boundary",
            "root_at",
            "fit",
            "no_frame",
            "frame_radius",
            "upright",
            "onto",
            "direction",
            "sag",
        ],
        "buds" => &["cells", "seed", "cell_mm", "clearance", "no_textures"],
        "cells" => &["point_tolerance"],
        "simplify" => &[
            "max_deviation",
            "min_length",
            "merge_distance",
            "min_angle",
            "prune_order",
        ],
        "planarize" => &[
            "method",
            "height",
            "height_from_radius",
            "tolerance",
            "alpha",
            "step",
            "plain_projection",
            "max_iterations",
            "fix_normal",
            "fix_axis",
            "timings",
            "name",
        ],
        "audit" => &["tolerance", "tolerance_rules", "metric", "name"],
        "size" => &[
            "material",
            "gauges",
            "support",
            "load",
            "deflection_limit",
            "group_by",
            "groups",
            "smooth",
            "throat",
            "max_rounds",
            "shells",
            "weld_gap",
            "weld_gap_tolerance",
            "node_core",
            "bolt",
            "bolt_clearance",
            "name",
        ],
        "plates" => &[
            "gauges",
            "thickness",
            "edge_thickness",
            "weld_gap",
            "weld_gap_tolerance",
            "node_core",
            "min_weld_angle",
            "groups",
            "bolt",
            "bolt_clearance",
            "material",
        ],
        "nest" => &[
            "sheet",
            "stock",
            "margin",
            "spacing",
            "rotations",
            "keep_groups",
            "tries",
            "seed",
            "no_pairs",
            "remnant_min",
            "lead_in",
            "micro_joints",
            "micro_joint_below",
            "micro_joint_width",
            "speeds",
            "kerf",
            "cut_order",
            "common_line",
            "job",
            "date",
            "time",
            "nc",
            "post",
            "nc_on",
            "nc_off",
        ],
        "solid" => &[
            "cell",
            "tolerance",
            "lamina",
            "base",
            "fit",
            "upright",
            "radius",
            "supports",
            "support_tip",
            "support_pillar",
            "support_join",
            "support_clearance",
            "support_spacing",
            "support_base",
        ],
        "slice" => &[
            "printer",
            "layer",
            "pixel",
            "resolution",
            "exposure",
            "bottom_exposure",
            "bottom_layers",
            "lift",
            "lift_speed",
            "copies",
            "gap",
            "resin_cost",
            "density",
            "speed",
            "material",
            "name",
            "keep_position",
            "scale",
            "weld",
            "weld_rel",
            "supports",
            "support_tip",
            "support_pillar",
            "support_join",
            "support_clearance",
            "support_spacing",
            "support_base",
        ],
        "print" => &[
            "printer",
            "layer",
            "pixel",
            "resolution",
            "exposure",
            "bottom_exposure",
            "bottom_layers",
            "lift",
            "lift_speed",
            "copies",
            "gap",
            "resin_cost",
            "density",
            "speed",
            "material",
            "name",
            "lamina",
            "base",
            "fit",
            "upright",
            "radius",
            "supports",
            "support_tip",
            "support_pillar",
            "support_join",
            "support_clearance",
            "support_spacing",
            "support_base",
        ],
        _ => &[],
    }
}

pub fn venation(o: &mut Opts) -> PyResult<stage::venation::Options> {
    use stage::venation::{BladeGrowth, Channel, Mode, Placement};
    let d = stage::venation::Options::default();
    let mode = match o.string("mode")?.as_deref() {
        None | Some("closed") => Mode::Closed,
        Some("open") => Mode::Open,
        Some(m) => return Err(crate::error(format!("mode= {m:?}: give open or closed"))),
    };
    let placement = match o.string("placement")?.as_deref() {
        None => None,
        Some("poisson") => Some(Placement::Poisson),
        Some("random") => Some(Placement::Random),
        Some(p) => {
            return Err(crate::error(format!(
                "placement= {p:?}: give poisson or random"
            )))
        }
    };
    let blade = match o.string("blade")?.as_deref() {
        None => None,
        Some("none") => Some(BladeGrowth::None),
        Some("uniform") => Some(BladeGrowth::Uniform),
        Some("marginal") => Some(BladeGrowth::Marginal),
        Some(b) => {
            return Err(crate::error(format!(
                "blade= {b:?}: give none, uniform or marginal"
            )))
        }
    };
    let density_channel = match o.string("density_channel")?.as_deref() {
        None => None,
        Some("red") => Some(Channel::Red),
        Some("green") => Some(Channel::Green),
        Some("blue") => Some(Channel::Blue),
        Some("luminance") => Some(Channel::Luminance),
        Some(c) => {
            return Err(crate::error(format!(
                "density_channel= {c:?}: give luminance, red, green or blue"
            )))
        }
    };
    let density = match o.string("density")? {
        Some(path) => Some(
            lamina::grow::density::DensityMap::read(std::path::Path::new(&path))
                .map_err(|e| crate::error(e.to_string()))?,
        ),
        None => None,
    };
    // Roots in a blade: (x, y) points; on a surface they come apart (see `surface_root`).
    let root = match o.typed("root", "a list of (x, y) points", |v| {
        v.extract::<Vec<[f64; 2]>>()
    })? {
        Some(r) => r.into_iter().map(|[x, y]| DVec2::new(x, y)).collect(),
        None => Vec::new(),
    };
    Ok(stage::venation::Options {
        mode,
        root,
        step: o.f64("step")?,
        kill: o.f64("kill")?,
        birth: o.f64("birth")?,
        density,
        birth_min: o.f64("birth_min")?,
        birth_max: o.f64("birth_max")?,
        sources: o.usize("sources")?,
        placement,
        sources_per_step: o.usize("sources_per_step")?,
        blade,
        initial_scale: o.f64("initial_scale")?.unwrap_or(d.initial_scale),
        blade_rate: o.f64("blade_rate")?.unwrap_or(d.blade_rate),
        r: o.f64("r")?,
        join_distance: o.f64("join_distance")?,
        join_angle: o.f64("join_angle")?.unwrap_or(d.join_angle),
        min_joint_angle: o.f64("min_joint_angle")?,
        min_member: o.f64("min_member")?.unwrap_or(d.min_member),
        murray: o.f64("murray")?.unwrap_or(d.murray),
        tip_radius: o.f64("tip_radius")?,
        max_iterations: o.usize("max_iterations")?.unwrap_or(d.max_iterations),
        seed: o.u64("seed")?.unwrap_or(d.seed),
        density_channel,
        reach: o.f64("reach")?,
        edge_tolerance: o.f64("edge_tolerance")?,
    })
}

pub fn veins(o: &mut Opts) -> PyResult<stage::veins::Options> {
    use stage::veins::Channel;
    let d = stage::veins::Options::default();
    let density_channel = match o.string("density_channel")?.as_deref() {
        None => None,
        Some("red") => Some(Channel::Red),
        Some("green") => Some(Channel::Green),
        Some("blue") => Some(Channel::Blue),
        Some("luminance") => Some(Channel::Luminance),
        Some(c) => {
            return Err(crate::error(format!(
                "density_channel= {c:?}: give luminance, red, green or blue"
            )))
        }
    };
    Ok(stage::veins::Options {
        source: o
            .typed("source", "a list of vertex indices", |v| {
                v.extract::<Vec<u32>>()
            })?
            .unwrap_or_default(),
        sources: o.usize("sources")?,
        density_channel,
        root: o.u32("root")?,
        tip_radius: o.f64("tip_radius")?,
        murray: o.f64("murray")?.unwrap_or(d.murray),
        smooth: o.usize("smooth")?.unwrap_or(d.smooth),
        seed: o.u64("seed")?.unwrap_or(d.seed),
    })
}

/// The shaping of a drawn tree (widths, façade, projection): boundary as N×2 points or
/// `(w, h)` for a rectangle, the surface as (vertices, faces).
pub fn shape(o: &mut Opts) -> PyResult<stage::branching::Shape> {
    use stage::branching::{rect, Fit};
    let boundary = match o.take("boundary")? {
        None => None,
        Some(v) => {
            if let Ok([w, h]) = v.extract::<[f64; 2]>() {
                Some(rect(w, h).map_err(|e| crate::error(e.to_string()))?)
            } else {
                let pts: Vec<[f64; 2]> = v.extract().map_err(|_| {
                    crate::error("boundary= must be (width, height) or an N×2 polygon".into())
                })?;
                Some(
                    lamina::grow::outline::Outline::new(
                        pts.into_iter().map(|[x, y]| DVec2::new(x, y)).collect(),
                    )
                    .map_err(|e| crate::error(format!("boundary= {e}")))?,
                )
            }
        }
    };
    let fit = match o.take("fit")? {
        None => None,
        Some(v) => Some(match v.extract::<String>().as_deref() {
            Ok("cover") => Fit::Cover,
            Ok("contain") => Fit::Contain,
            _ => match v.extract::<f64>() {
                Ok(s) if s.is_finite() && s > 0.0 => Fit::Scale(s),
                _ => {
                    return Err(crate::error(
                        "fit= must be \"cover\", \"contain\" or a positive scale factor".into(),
                    ))
                }
            },
        }),
    };
    let onto = match o.take("onto")? {
        None => None,
        Some(v) => {
            let (vb, fb): (
                Bound<'_, pyo3::types::PyBytes>,
                Bound<'_, pyo3::types::PyBytes>,
            ) = v
                .extract()
                .map_err(|_| crate::error("onto= must be a mesh (vertices, faces)".into()))?;
            let mut mesh = crate::mesh_from("onto", vb.as_bytes(), fb.as_bytes(), &[])?;
            mesh.drop_degenerate();
            Some(mesh)
        }
    };
    Ok(stage::branching::Shape {
        murray: o.f64("murray")?,
        tip_radius: o.f64("tip_radius")?,
        boundary,
        root_at: o.vector::<2>("root_at")?.map(DVec2::from_array),
        fit,
        no_frame: o.bool("no_frame")?,
        frame_radius: o.f64("frame_radius")?,
        upright: o.bool("upright")?,
        onto,
        direction: o.vector::<3>("direction")?.map(DVec3::from_array),
        sag: o.f64("sag")?,
    })
}

pub fn lsystem(o: &mut Opts) -> PyResult<stage::lsystem::Options> {
    let d = stage::lsystem::Options::default();
    Ok(stage::lsystem::Options {
        axiom: o.string("axiom")?,
        rule: o.strings("rule")?,
        iterations: o.u32("iterations")?,
        angle: o.parsed("angle", |s| s.parse())?,
        step: o.f64("step")?,
        length_scale: o.f64("length_scale")?.unwrap_or(d.length_scale),
        no_simplify: o.bool("no_simplify")?,
        radius: o.f64("radius")?.unwrap_or(d.radius),
        radius_scale: o.f64("radius_scale")?.unwrap_or(d.radius_scale),
        decay: o.f64("decay")?.unwrap_or(d.decay),
        seed: o.u64("seed")?.unwrap_or(d.seed),
        max_symbols: o.u64("max_symbols")?.unwrap_or(d.max_symbols),
        ..d
    })
}

pub fn bifurcate(o: &mut Opts) -> PyResult<stage::bifurcate::Options> {
    let d = stage::bifurcate::Options::default();
    Ok(stage::bifurcate::Options {
        depth: o.u32("depth")?.unwrap_or(d.depth),
        length: o.f64("length")?.unwrap_or(d.length),
        angle: o.parsed("angle", |s| s.parse())?.unwrap_or(d.angle),
        scale: o.parsed("scale", |s| s.parse())?.unwrap_or(d.scale),
        radius: o.f64("radius")?.unwrap_or(d.radius),
        radius_scale: o.f64("radius_scale")?.unwrap_or(d.radius_scale),
        roll: o.f64("roll")?,
        seed: o.u64("seed")?.unwrap_or(d.seed),
        ..d
    })
}

pub fn buds(o: &mut Opts) -> PyResult<stage::buds::Options> {
    let d = stage::buds::Options::default();
    Ok(stage::buds::Options {
        cells: o.usize("cells")?.unwrap_or(d.cells),
        seed: o.u64("seed")?.unwrap_or(d.seed),
        cell_mm: o.f64("cell_mm")?.unwrap_or(d.cell_mm),
        clearance: o.f64("clearance")?.unwrap_or(d.clearance),
        no_textures: o.bool("no_textures")?,
        ..d
    })
}

pub fn simplify(o: &mut Opts) -> PyResult<stage::simplify::Options> {
    let d = stage::simplify::Options::default();
    Ok(stage::simplify::Options {
        max_deviation: o.f64("max_deviation")?,
        min_length: o.f64("min_length")?.unwrap_or(d.min_length),
        merge_distance: o.f64("merge_distance")?.unwrap_or(d.merge_distance),
        min_angle: o.f64("min_angle")?.unwrap_or(d.min_angle),
        prune_order: o.u32("prune_order")?.unwrap_or(d.prune_order),
    })
}

/// `SELECTOR:X,Y,Z`, as `--fix-normal` takes it.
fn selector_vector(option: &str, s: &str) -> Result<(Selector, DVec3), String> {
    let Some((sel, dir)) = s.rsplit_once(':') else {
        return Err(format!("{option}= \"{s}\": expected SELECTOR:X,Y,Z"));
    };
    let sel = Selector::parse(sel).map_err(|e| format!("{option}= \"{s}\": {e}"))?;
    let v: Vec<f64> = dir
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{option}= \"{s}\": \"{dir}\" is not X,Y,Z"))?;
    let [x, y, z] = v[..] else {
        return Err(format!("{option}= \"{s}\": \"{dir}\" is not X,Y,Z"));
    };
    Ok((sel, DVec3::new(x, y, z)))
}

pub fn planarize(o: &mut Opts) -> PyResult<stage::planarize::Options> {
    use stage::planarize::Method;
    let d = stage::planarize::Options::default();
    let method = match o.string("method")?.as_deref() {
        None => d.method,
        Some("lbfgs") => Method::Lbfgs,
        Some("projection") => Method::Projection,
        Some("newton") => Method::Newton,
        Some(m) => {
            return Err(crate::error(format!(
                "method= {m:?}: give lbfgs, projection or newton"
            )))
        }
    };
    let pairs = |list: Vec<String>, option: &str| {
        list.iter()
            .map(|s| selector_vector(option, s).map_err(crate::error))
            .collect::<PyResult<Vec<_>>>()
    };
    Ok(stage::planarize::Options {
        method,
        height: o.f64("height")?.unwrap_or(d.height),
        height_from_radius: o.f64("height_from_radius")?,
        tolerance: o.f64("tolerance")?.unwrap_or(d.tolerance),
        alpha: o.f64("alpha")?.unwrap_or(d.alpha),
        step: o.f64("step")?.unwrap_or(d.step),
        plain_projection: o.bool("plain_projection")?,
        max_iterations: o.usize("max_iterations")?.unwrap_or(d.max_iterations),
        fix_normal: pairs(o.strings("fix_normal")?, "fix_normal")?,
        fix_axis: pairs(o.strings("fix_axis")?, "fix_axis")?,
        name: o.string("name")?.unwrap_or(d.name),
        timings: o.bool("timings")?,
    })
}

pub fn audit(o: &mut Opts) -> PyResult<stage::audit::Options> {
    use stage::audit::Metric;
    let d = stage::audit::Options::default();
    let metric = match o.string("metric")?.as_deref() {
        None => d.metric,
        Some("flatness") => Metric::Flatness,
        Some("best-fit") | Some("best_fit") => Metric::BestFit,
        Some("corner") => Metric::Corner,
        Some(m) => {
            return Err(crate::error(format!(
                "metric= {m:?}: give flatness, best-fit or corner"
            )))
        }
    };
    let (rules, rules_name) = match o.take("tolerance_rules")? {
        None => (None, d.rules_name.clone()),
        Some(v) => {
            if let Ok(path) = v.extract::<String>() {
                let r = lamina::rationalize::tolerance::Rules::read(std::path::Path::new(&path))
                    .map_err(|e| crate::error(e.to_string()))?;
                (Some(r), path)
            } else {
                let value = crate::convert::from_py(&v, "tolerance_rules")?;
                let r = serde_json::from_value(value)
                    .map_err(|e| crate::error(format!("tolerance_rules= {e}")))?;
                (Some(r), "tolerance_rules".to_string())
            }
        }
    };
    Ok(stage::audit::Options {
        tolerance: o.f64("tolerance")?,
        tolerance_rules: rules,
        rules_name,
        metric,
        name: o.string("name")?.unwrap_or(d.name),
    })
}

/// `material=`: a built-in steel's name or a material file's path.
fn material(o: &mut Opts) -> PyResult<Option<lamina::analyze::material::Material>> {
    o.string("material")?
        .map(|m| {
            lamina::analyze::material::Material::get(&m)
                .map_err(|e| crate::error(format!("material= {e}")))
        })
        .transpose()
}

pub fn size(o: &mut Opts) -> PyResult<stage::size::Options> {
    use lamina::analyze::sizing::DeflectionLimit;
    let d = stage::size::Options::default();
    let material = material(o)?;
    let support = o
        .strings("support")?
        .iter()
        .map(|s| stage::size::support(s).map_err(|e| crate::error(format!("support= {e}"))))
        .collect::<PyResult<Vec<_>>>()?;
    let deflection_limit = match o.take("deflection_limit")? {
        None => None,
        Some(v) => match v.extract::<f64>() {
            Ok(mm) if !v.is_instance_of::<pyo3::types::PyString>() => {
                Some(DeflectionLimit::Millimetres(mm))
            }
            _ => {
                let s: String = v.extract().map_err(|_| {
                    crate::error("deflection_limit= must be \"L/N\" or a length in mm".into())
                })?;
                Some(
                    DeflectionLimit::parse(&s)
                        .map_err(|e| crate::error(format!("deflection_limit= {e}")))?,
                )
            }
        },
    };
    Ok(stage::size::Options {
        material,
        gauges: o.f64s("gauges")?.unwrap_or(d.gauges),
        support,
        load: o.strings("load")?,
        deflection_limit,
        group_by: o
            .parsed("group_by", stage::size::group_by)?
            .unwrap_or(d.group_by),
        groups: o.usize("groups")?,
        smooth: o.bool("smooth")?,
        throat: o.f64("throat")?.unwrap_or(d.throat),
        max_rounds: o.usize("max_rounds")?.unwrap_or(d.max_rounds),
        shells: o.usize("shells")?,
        joints: stage::plates::Joints {
            weld_gap: o.f64("weld_gap")?.unwrap_or(d.joints.weld_gap),
            weld_gap_tolerance: o
                .f64("weld_gap_tolerance")?
                .unwrap_or(d.joints.weld_gap_tolerance),
            node_core: o.parsed("node_core", lamina::rationalize::plates::CoreSize::parse)?,
            bolt: o.parsed("bolt", lamina::rationalize::bolts::parse)?,
            bolt_clearance: o.parsed(
                "bolt_clearance",
                lamina::rationalize::clearance::Socket::parse,
            )?,
        },
        name: o.string("name")?.unwrap_or(d.name),
    })
}

pub fn plates(o: &mut Opts) -> PyResult<stage::plates::Options> {
    use lamina::rationalize::plates::{CoreSize, EdgeSelector};
    let d = stage::plates::Options::default();
    let edge_thickness = o
        .strings("edge_thickness")?
        .iter()
        .map(|s| {
            let (sel, t) = s.rsplit_once(':').ok_or_else(|| {
                crate::error(format!(
                    "edge_thickness= \"{s}\": expected SELECTOR:MM, like z<1:6"
                ))
            })?;
            let t: f64 = t.trim().parse().map_err(|_| {
                crate::error(format!(
                    "edge_thickness= \"{s}\": \"{t}\" is not a thickness in mm"
                ))
            })?;
            Ok((
                EdgeSelector::parse(sel)
                    .map_err(|e| crate::error(format!("edge_thickness= {e}")))?,
                t,
            ))
        })
        .collect::<PyResult<Vec<_>>>()?;
    Ok(stage::plates::Options {
        gauges: o.f64s("gauges")?,
        thickness: o.f64("thickness")?,
        sizing: None,
        edge_thickness,
        weld_gap: o.f64("weld_gap")?.unwrap_or(d.weld_gap),
        weld_gap_tolerance: o.f64("weld_gap_tolerance")?.unwrap_or(d.weld_gap_tolerance),
        node_core: o.parsed("node_core", CoreSize::parse)?,
        min_weld_angle: o.f64("min_weld_angle")?,
        groups: o.usize("groups")?.unwrap_or(d.groups),
        bolt: o.parsed("bolt", lamina::rationalize::bolts::parse)?,
        bolt_clearance: o.parsed(
            "bolt_clearance",
            lamina::rationalize::clearance::Socket::parse,
        )?,
        material: material(o)?,
    })
}

/// The NC post-processor asked for by `nc=` (`gcode` or `essi`), `post=`, `nc_on=`, `nc_off=`.
pub fn nc_post(o: &mut Opts) -> PyResult<Option<lamina::fabricate::nc::Post>> {
    use lamina::fabricate::nc::{post_for, NcFormat};
    let format = o.string("nc")?;
    let (name, on, off) = (o.string("post")?, o.string("nc_on")?, o.string("nc_off")?);
    let Some(format) = format else {
        if let Some(key) = [("post", &name), ("nc_on", &on), ("nc_off", &off)]
            .iter()
            .find_map(|(k, v)| v.is_some().then_some(k))
        {
            return Err(crate::error(format!(
                "{key}= needs nc= (\"gcode\" or \"essi\")"
            )));
        }
        return Ok(None);
    };
    let format = NcFormat::parse(&format).ok_or_else(|| {
        crate::error(format!("nc= must be \"gcode\" or \"essi\", got {format:?}"))
    })?;
    post_for(format, name.as_deref(), on.as_deref(), off.as_deref())
        .map(Some)
        .map_err(|e| crate::error(format!("{}= {e}", e.field())))
}

pub fn nest(o: &mut Opts) -> PyResult<stage::nest::Options> {
    use stage::nest::{parse_rotations, parse_sheet, parse_stock, Stock};
    let d = stage::nest::Options::default();
    let sheet = o.parsed("sheet", parse_sheet)?;
    let stock = o
        .strings("stock")?
        .iter()
        .flat_map(|s| s.split(','))
        .map(|s| parse_stock(s).map_err(|e| crate::error(format!("stock= {e}"))))
        .collect::<PyResult<Vec<_>>>()?;
    let stock = match (stock.is_empty(), sheet) {
        (false, Some(_)) => {
            return Err(crate::error(
                "sheet= and stock= exclude each other: give one".into(),
            ))
        }
        (false, None) => stock,
        (true, Some(size)) => vec![Stock { size, cost: 0.0 }],
        (true, None) => d.stock.clone(),
    };
    let speeds = match o.take("speeds")? {
        None => None,
        Some(v) => {
            if let Ok(path) = v.extract::<String>() {
                Some(
                    lamina::fabricate::cutplan::SpeedTable::read(std::path::Path::new(&path))
                        .map_err(|e| crate::error(e.to_string()))?,
                )
            } else {
                let value = crate::convert::from_py(&v, "speeds")?;
                Some(
                    serde_json::from_value(value)
                        .map_err(|e| crate::error(format!("speeds= {e}")))?,
                )
            }
        }
    };
    Ok(stage::nest::Options {
        stock,
        margin: o.f64("margin")?.unwrap_or(d.margin),
        spacing: o.f64("spacing")?.unwrap_or(d.spacing),
        rotations: match o.take("rotations")? {
            None => d.rotations.clone(),
            Some(v) => match v.extract::<String>() {
                Ok(s) => {
                    parse_rotations(&s).map_err(|e| crate::error(format!("rotations= {e}")))?
                }
                Err(_) => {
                    stage::nest::Rotations::Listed(v.extract::<Vec<f64>>().map_err(|_| {
                        crate::error("rotations= must be \"any\" or a list of angles".into())
                    })?)
                }
            },
        },
        keep_groups: o.bool("keep_groups")?,
        tries: o.usize("tries")?,
        seed: o.u64("seed")?.unwrap_or(d.seed),
        no_pairs: o.bool("no_pairs")?,
        remnant_min: o
            .parsed("remnant_min", parse_sheet)?
            .unwrap_or(d.remnant_min),
        lead_in: o.f64("lead_in")?,
        micro_joints: o.usize("micro_joints")?,
        micro_joint_below: o.f64("micro_joint_below")?.unwrap_or(d.micro_joint_below),
        micro_joint_width: o.f64("micro_joint_width")?.unwrap_or(d.micro_joint_width),
        material: d.material.clone(),
        speeds,
        speeds_name: "speeds=".into(),
        kerf: o.f64("kerf")?.unwrap_or(d.kerf),
        cut_order: match o.string("cut_order")?.as_deref() {
            None => d.cut_order,
            Some("travel") => stage::nest::CutOrder::Travel,
            Some("spread") => stage::nest::CutOrder::Spread,
            Some(other) => {
                return Err(crate::error(format!(
                    "cut_order= must be \"travel\" or \"spread\", got {other:?}"
                )))
            }
        },
        common_line: o.bool("common_line")?,
        job: o.string("job")?,
        date: o.string("date")?,
        time: o.f64("time")?.unwrap_or(d.time),
    })
}

/// `supports=True` and the support_* keys (refused without it).
fn support_options(
    o: &mut Opts,
) -> PyResult<Option<lamina::fabricate::slice::supports::SupportOptions>> {
    use lamina::fabricate::slice::supports::SupportOptions;
    if o.bool("supports")? {
        let d = SupportOptions::default();
        let [b, bh] = o
            .vector::<2>("support_base")?
            .unwrap_or([d.base, d.base_height]);
        Ok(Some(SupportOptions {
            tip: o.f64("support_tip")?.unwrap_or(d.tip),
            pillar: o.f64("support_pillar")?.unwrap_or(d.pillar),
            base: b,
            base_height: bh,
            join: o.f64("support_join")?.unwrap_or(d.join),
            clearance: o.f64("support_clearance")?.unwrap_or(d.clearance),
            spacing: o.f64("support_spacing")?.unwrap_or(d.spacing),
        }))
    } else {
        for k in [
            "support_tip",
            "support_pillar",
            "support_join",
            "support_clearance",
            "support_spacing",
            "support_base",
        ] {
            if o.take(k)?.is_some() {
                return Err(crate::error(format!("{k}= needs supports=True")));
            }
        }
        Ok(None)
    }
}

fn solid_shape(o: &mut Opts) -> PyResult<stage::solid::Shape> {
    let base = o
        .vector::<2>("base")?
        .map(|[diameter, height]| stage::solid::Base { diameter, height });
    let supports = support_options(o)?;
    Ok(stage::solid::Shape {
        lamina: o.f64("lamina")?,
        base,
        fit: o.f64("fit")?,
        upright: o.bool("upright")?,
        radius: o.f64("radius")?,
        supports,
    })
}

pub fn solid(o: &mut Opts) -> PyResult<stage::solid::Options> {
    let d = stage::solid::Options::default();
    let cell = o.f64("cell")?.unwrap_or(d.cell);
    // As the command: simplified to a quarter cell unless told (tolerance=False: every
    // marched triangle, as --full).
    let tolerance = match o.take("tolerance")? {
        None => Some(0.25 * cell),
        Some(v) if v.is_instance_of::<pyo3::types::PyBool>() => {
            v.extract::<bool>()?.then_some(0.25 * cell)
        }
        Some(v) => Some(v.extract::<f64>().map_err(|_| {
            crate::error(
                "tolerance= must be a distance in mm, True for a quarter cell or False for \
                 every marched triangle"
                    .into(),
            )
        })?),
    };
    Ok(stage::solid::Options {
        cell,
        tolerance,
        shape: solid_shape(o)?,
    })
}

fn job(o: &mut Opts) -> PyResult<stage::slice::JobOptions> {
    use stage::slice::{JobOptions, Printer, PrinterOptions};
    let d = JobOptions::default();
    let (base, profile) = match o.take("printer")? {
        None => (Printer::default(), "dmp-sl".to_string()),
        Some(v) => {
            if let Ok(name) = v.extract::<String>() {
                if name == "dmp-sl" {
                    (Printer::default(), name)
                } else {
                    let text = std::fs::read_to_string(&name).map_err(|e| {
                        crate::error(format!(
                            "printer= {name}: not \"dmp-sl\" and not a readable JSON profile ({e})"
                        ))
                    })?;
                    let p: Printer = serde_json::from_str(&text)
                        .map_err(|e| crate::error(format!("{name}: not a printer profile: {e}")))?;
                    (p, name)
                }
            } else {
                let value = crate::convert::from_py(&v, "printer")?;
                let p: Printer = serde_json::from_value(value)
                    .map_err(|e| crate::error(format!("printer= not a printer profile: {e}")))?;
                (p, "printer=".to_string())
            }
        }
    };
    let overrides = PrinterOptions {
        layer: o.f64("layer")?,
        pixel: o.f64("pixel")?,
        resolution: o.typed("resolution", "(width, height) in pixels", |v| {
            v.extract::<(u32, u32)>()
        })?,
        exposure: o.f64("exposure")?,
        bottom_exposure: o.f64("bottom_exposure")?,
        bottom_layers: o.u32("bottom_layers")?,
        lift: o.f64("lift")?,
        lift_speed: o.f64("lift_speed")?,
    };
    let printer = overrides
        .apply(base, &profile)
        .map_err(|e| crate::error(e.to_string()))?;
    Ok(JobOptions {
        printer,
        copies: o.usize("copies")?.unwrap_or(d.copies),
        gap: o.f64("gap")?.unwrap_or(d.gap),
        resin_cost: o.f64("resin_cost")?.unwrap_or(d.resin_cost),
        density: o.f64("density")?.unwrap_or(d.density),
        speed: o.f64("speed")?,
        material: o.string("material")?.unwrap_or(d.material),
        name: o.string("name")?.unwrap_or(d.name),
    })
}

pub fn slice(o: &mut Opts) -> PyResult<stage::slice::Options> {
    Ok(stage::slice::Options {
        job: job(o)?,
        keep_position: o.bool("keep_position")?,
        units: None,
        scale: o.f64("scale")?,
        weld: match (o.f64("weld")?, o.f64("weld_rel")?) {
            (Some(_), Some(_)) => {
                return Err(crate::error(
                    "weld and weld_rel: give one (a distance in mm, or a fraction of the diagonal)"
                        .into(),
                ))
            }
            (Some(mm), None) => Some(lamina::network::Weld::Absolute(mm)),
            (None, Some(f)) => Some(lamina::network::Weld::Relative(f)),
            (None, None) => None,
        },
        supports: support_options(o)?,
    })
}

pub fn print(o: &mut Opts) -> PyResult<stage::print::Options> {
    use stage::print::DisplayFit;
    let job = job(o)?;
    // fit="auto" fills the display, fit="keep" prints as drawn; a number is the longest side.
    let display_fit = match o.word("fit")?.as_deref() {
        None => DisplayFit::Shrink,
        Some("auto") => DisplayFit::Fill,
        Some("keep") => DisplayFit::Keep,
        Some(other) => {
            return Err(crate::error(format!(
                "fit={other:?}: expected the longest side in mm, \"auto\" or \"keep\""
            )))
        }
    };
    Ok(stage::print::Options {
        display_fit,
        shape: solid_shape(o)?,
        name: Some(job.name.clone()),
        job,
    })
}
