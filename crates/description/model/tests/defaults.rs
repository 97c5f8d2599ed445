//! Parsed defaults and their cache: a model that keeps a [`DefaultsCache`] parses its
//! parameters and damping once, a case's overrides never leak into the cache, and a model
//! without a cache (a downstream model written before caching existed) works as before.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::{Matrix6, Vector3, Vector6};
use num_dual::Dual64;
use pendkit_model::{
    BodySpec, BuildError, DampingSpec, Defaults, DefaultsCache, Model, Overrides, SystemBuilder,
    build_stepped, build_with,
};
use pendkit_params::{ParamError, ParamSet, Resolved};
use pendkit_system::{Real, SpringEnd, System};

/// A mass `m` (kg) on a spring `k` (N/m) along x with structural loss `phi` on tag
/// `spring`, counting how often its defaults are asked for.
struct Oscillator {
    name: &'static str,
    cache: Option<DefaultsCache>,
    parameter_calls: AtomicUsize,
    damping_calls: AtomicUsize,
    /// Text of the definition of `k` (a broken one tests error reporting).
    k: &'static str,
}

impl Oscillator {
    fn new(name: &'static str, cached: bool) -> Self {
        Oscillator {
            name,
            cache: cached.then(DefaultsCache::new),
            parameter_calls: AtomicUsize::new(0),
            damping_calls: AtomicUsize::new(0),
            k: "100",
        }
    }
}

impl Model for Oscillator {
    fn name(&self) -> &'static str {
        self.name
    }
    fn summary(&self) -> &'static str {
        "mass on a spring"
    }
    fn parameters(&self) -> Result<ParamSet, ParamError> {
        self.parameter_calls.fetch_add(1, Ordering::SeqCst);
        let mut p = ParamSet::new();
        p.define("m", "1")?;
        p.define("k", self.k)?;
        p.define("phi", "1e-3")?;
        Ok(p)
    }
    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        self.damping_calls.fetch_add(1, Ordering::SeqCst);
        BTreeMap::from([("spring".to_string(), DampingSpec::structural("phi"))])
    }
    fn build(&self, p: &Resolved) -> Result<System, BuildError> {
        oscillator_system(p.get("m")?, p.get("k")?)
    }
    fn defaults_cache(&self) -> Option<&DefaultsCache> {
        self.cache.as_ref()
    }
}

/// The oscillator's mechanics over any scalar: a mass `m` (kg) on a spring `k` (N/m) along x
/// to the support `s`, tag `spring`.
fn oscillator_system<S: Real>(m: S, k: S) -> Result<System<S>, BuildError> {
    let mut b = SystemBuilder::new(S::from(0.0));
    b.variable("x", 0.0)?;
    b.parameter("s", 0.0)?;
    let ground = b.body(BodySpec::new("ground").pose(["s", "0", "0", "0", "0", "0"]))?;
    let mass = b.body(
        BodySpec::new("mass")
            .pose(["x", "0", "0", "0", "0", "0"])
            .mass(m),
    )?;
    let end = |body| SpringEnd {
        body,
        point: Vector3::zeros(),
        angles: [S::from(0.0); 3],
    };
    let mut stiffness = Matrix6::zeros();
    stiffness[(0, 0)] = k;
    b.spring(
        "k",
        [end(ground), end(mass)],
        stiffness,
        Vector6::zeros(),
        "spring",
    )?;
    b.build()
}

fn overrides(parameters: &[(&str, &str)], structural: Option<&str>) -> Overrides {
    let mut o = Overrides {
        parameters: parameters
            .iter()
            .map(|(n, v)| (n.to_string(), v.to_string()))
            .collect(),
        ..Default::default()
    };
    if let Some(phi) = structural {
        o.damping
            .insert("spring".into(), DampingSpec::structural(phi));
    }
    o
}

/// (mass in kg, loss angle of tag `spring`) of a build.
fn mass_and_loss(model: &dyn Model, o: &Overrides) -> (f64, f64) {
    let (system, _) = build_with(model, o).expect("builds");
    (system.bodies[1].mass, system.damping.at("spring", 10.0).1)
}

#[test]
fn a_cached_model_parses_its_defaults_once() {
    let model = Oscillator::new("cached", true);
    for _ in 0..3 {
        assert_eq!(mass_and_loss(&model, &Overrides::default()), (1.0, 1e-3));
    }
    assert_eq!(model.parameter_calls.load(Ordering::SeqCst), 1);
    assert_eq!(model.damping_calls.load(Ordering::SeqCst), 1);
}

#[test]
fn a_model_without_a_cache_parses_every_time_and_builds_the_same() {
    let plain = Oscillator::new("plain", false);
    let cached = Oscillator::new("cached", true);
    for o in [
        Overrides::default(),
        overrides(&[("m", "scale(3)")], Some("2*phi")),
    ] {
        assert_eq!(mass_and_loss(&plain, &o), mass_and_loss(&cached, &o));
    }
    assert_eq!(plain.parameter_calls.load(Ordering::SeqCst), 2);
    assert_eq!(plain.damping_calls.load(Ordering::SeqCst), 2);
}

#[test]
fn overrides_do_not_leak_into_the_cache() {
    let model = Oscillator::new("cached", true);
    // parameter and damping overrides apply to their own build only
    let changed = overrides(&[("m", "increment(1)"), ("phi", "5e-3")], Some("phi/5"));
    assert_eq!(mass_and_loss(&model, &changed), (2.0, 1e-3));
    assert_eq!(
        mass_and_loss(&model, &overrides(&[], Some("phi*2"))),
        (1.0, 2e-3)
    );
    // scale() composes with the default, not with an earlier build's override
    assert_eq!(
        mass_and_loss(&model, &overrides(&[("m", "scale(4)")], None)),
        (4.0, 1e-3)
    );
    assert_eq!(mass_and_loss(&model, &Overrides::default()), (1.0, 1e-3));
    let defaults = Defaults::of(&model).expect("defaults");
    assert_eq!(defaults.params.get("m").expect("m").source, "1");
}

#[test]
fn a_cache_holding_another_models_defaults_is_bypassed() {
    // Two models sharing one cache by mistake: the second still gets its own defaults.
    static SHARED: DefaultsCache = DefaultsCache::new();
    struct Renamed(Oscillator);
    impl Model for Renamed {
        fn name(&self) -> &'static str {
            self.0.name
        }
        fn summary(&self) -> &str {
            self.0.summary()
        }
        fn parameters(&self) -> Result<ParamSet, ParamError> {
            self.0.parameters()
        }
        fn damping(&self) -> BTreeMap<String, DampingSpec> {
            self.0.damping()
        }
        fn build(&self, p: &Resolved) -> Result<System, BuildError> {
            self.0.build(p)
        }
        fn defaults_cache(&self) -> Option<&DefaultsCache> {
            Some(&SHARED)
        }
    }
    let first = Renamed(Oscillator::new("first", false));
    let mut second = Renamed(Oscillator::new("second", false));
    second.0.k = "400";
    assert_eq!(
        Defaults::of(&first)
            .expect("first")
            .params
            .get("k")
            .expect("k")
            .source,
        "100"
    );
    let defaults = Defaults::of(&second).expect("second");
    assert_eq!(
        (
            defaults.model.as_str(),
            defaults.params.get("k").expect("k").source.as_str()
        ),
        ("second", "400")
    );
}

#[test]
fn defaults_that_do_not_parse_give_the_same_error_every_time() {
    let mut model = Oscillator::new("broken", true);
    model.k = "2*(";
    let first = build_with(&model, &Overrides::default()).unwrap_err();
    let second = build_with(&model, &Overrides::default()).unwrap_err();
    assert_eq!(first, second);
    assert!(first.to_string().starts_with("parameter 'k': "), "{first}");
}

#[test]
fn temperature_and_early_wire_terms_are_part_of_the_defaults() {
    let model = Oscillator::new("cached", true);
    let defaults = Defaults::of(&model).expect("defaults");
    let r = defaults.params.resolve().expect("resolves");
    assert_eq!(r.get("temperature"), Ok(pendkit_model::DEFAULT_TEMPERATURE));
    assert_eq!(r.get("wire_terms_early"), Ok(0.0));
}

#[test]
fn the_mechanical_reads_are_the_model_builds_own() {
    // what the sensitivities take for the parameters that move the mechanics: the reads of
    // the model's own build (here m and k), not the damping's loss angle nor the built-in
    // temperature and switch that the build then attaches (which the whole build reads)
    use pendkit_model::build_with_mechanical_reads;
    let model = Oscillator::new("reads", false);
    let (_, resolved, mechanical) =
        build_with_mechanical_reads(&model, &Overrides::default()).expect("builds");
    assert_eq!(mechanical, ["m", "k"]);
    let all = resolved.read_names();
    for name in ["m", "k", "phi", "temperature", "wire_terms_early"] {
        assert!(
            all.contains(&name),
            "{name} not read by the whole build: {all:?}"
        );
    }
    // a switch off its values is refused, as by build_with, with the reads left as they are
    let o = overrides(&[("wire_terms_early", "0.5")], None);
    let e = build_with_mechanical_reads(&model, &o)
        .unwrap_err()
        .to_string();
    assert_eq!(e, build_with(&model, &o).unwrap_err().to_string());
    assert!(e.contains("wire_terms_early") && e.contains("0.5"), "{e}");
}

#[test]
fn a_stepped_build_moves_along_the_tangent_and_attaches_the_stepped_damping() {
    // the mechanics built with m seeded (dm/dm = 1, k's tangent 0) and moved by 1/4 kg:
    // m = 1 + 1/4 = 1.25 kg with no rounding (binary fractions); the damping and the
    // temperature attached at the overrides' parameters, as a rebuild at m = 1.25 attaches
    // them: the loss angle is the override's 2e-3, read back as written
    let model = Oscillator::new("stepped", false);
    let defaults = Defaults::of(&model).expect("defaults");
    let dual = oscillator_system(Dual64::new(1.0, 1.0), Dual64::new(100.0, 0.0)).expect("dual");
    let o = overrides(&[("m", "1.25"), ("phi", "2e-3")], None);
    let stepped = build_stepped(&dual, 0.25, &defaults, &o).expect("stepped");
    assert_eq!(stepped.bodies[1].mass, 1.25);
    assert_eq!(stepped.damping.at("spring", 10.0), (1.0, 2e-3));
    let (rebuilt, _) = build_with(&model, &o).expect("rebuilt");
    assert_eq!(stepped.temperature, rebuilt.temperature);
    // a stepped value the parameters refuse is the build's error, as for a rebuild
    let unknown = overrides(&[("no_such", "1")], None);
    assert!(build_stepped(&dual, 0.25, &defaults, &unknown).is_err());
}
