//! Damping specifications as a model or case writes them, parsed once and compiled against
//! the model's resolved parameters into multipliers of frequency.

use std::sync::{Arc, OnceLock};

use pendkit_expr::{BinOp, Expr, Slot, parse};
use pendkit_params::Resolved;
use pendkit_system::TagDamping;

use crate::BuildError;
use crate::schema::{self, DAMPING_FIELDS, DAMPING_TEMPERATURE, Domain, Field};

/// The damping of one tag: each field an expression over the model's parameters; `real`
/// and `imag` may also use `f` (Hz). The imaginary multiplier is the sum of the parts given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DampingSpec {
    /// ε'(f); 1 when absent.
    pub real: Option<String>,
    /// Structural loss angle φ (frequency independent).
    pub structural: Option<String>,
    /// Viscous loss: ε'' = viscous · f, i.e. the loss angle at 1 Hz (for a spring k with
    /// dashpot c, viscous = 2π c / k).
    pub viscous: Option<String>,
    /// Thermoelastic relaxation strength Δ: ε'' = Δ ωτ / (1 + (ωτ)²), ω = 2π f; 0 when
    /// only τ is given.
    pub thermoelastic_delta: Option<String>,
    /// Thermoelastic relaxation time τ (s); 0 when only Δ is given.
    pub thermoelastic_tau: Option<String>,
    /// Any further ε''(f).
    pub imag: Option<String>,
    /// Temperature (K) of the terms with this tag for thermal noise, an expression over the
    /// model's parameters (not `f`); the model's `temperature` when absent.
    pub temperature: Option<String>,
}

impl DampingSpec {
    /// Structural damping with loss angle `phi` (an expression).
    pub fn structural(phi: &str) -> Self {
        DampingSpec {
            structural: Some(phi.to_string()),
            ..Default::default()
        }
    }

    /// Thermoelastic damping with strength `delta` and relaxation time `tau` (s), both
    /// expressions.
    pub fn thermoelastic(delta: &str, tau: &str) -> Self {
        DampingSpec {
            thermoelastic_delta: Some(delta.to_string()),
            thermoelastic_tau: Some(tau.to_string()),
            ..Default::default()
        }
    }

    /// Replaces the fields that `other` sets, each on its own (a case that sets only
    /// `thermoelastic.tau` keeps the model's Δ).
    pub fn merge(&mut self, other: &DampingSpec) {
        for (field, text) in other.fields() {
            if let Some(slot) = self.slot(field.name) {
                *slot = Some(text.to_string());
            }
        }
    }

    /// Sets one field by its name in [`DAMPING_FIELDS`] (`real`, `structural`, `viscous`,
    /// `imag`, `thermoelastic.delta`, `thermoelastic.tau`, `temperature`): what case files,
    /// suspension files and `--set damping.<tag>.<field>=...` all call.
    pub fn set_field(&mut self, field: &str, text: &str) -> Result<(), String> {
        match self.slot(field) {
            Some(slot) => {
                *slot = Some(text.to_string());
                Ok(())
            }
            None => Err(format!(
                "unknown damping field '{field}' ({})",
                schema::names(DAMPING_FIELDS)
            )),
        }
    }

    /// The place of the field called `name` in [`DAMPING_FIELDS`] (a test checks that every
    /// field of the table has one, and [`DampingSpec::field`] reads it).
    fn slot(&mut self, name: &str) -> Option<&mut Option<String>> {
        Some(match name {
            "real" => &mut self.real,
            "structural" => &mut self.structural,
            "viscous" => &mut self.viscous,
            "imag" => &mut self.imag,
            "temperature" => &mut self.temperature,
            "thermoelastic.delta" => &mut self.thermoelastic_delta,
            "thermoelastic.tau" => &mut self.thermoelastic_tau,
            _ => return None,
        })
    }

    /// The expression text of the field called `name` in [`DAMPING_FIELDS`], if it is set.
    pub fn field(&self, name: &str) -> Option<&str> {
        match name {
            "real" => self.real.as_deref(),
            "structural" => self.structural.as_deref(),
            "viscous" => self.viscous.as_deref(),
            "imag" => self.imag.as_deref(),
            "temperature" => self.temperature.as_deref(),
            "thermoelastic.delta" => self.thermoelastic_delta.as_deref(),
            "thermoelastic.tau" => self.thermoelastic_tau.as_deref(),
            _ => None,
        }
    }

    /// The fields that are set, in the order of [`DAMPING_FIELDS`], with their expression
    /// texts: what a writer of case files writes (`fit --out`).
    pub fn fields(&self) -> impl Iterator<Item = (&'static Field, &str)> {
        DAMPING_FIELDS
            .iter()
            .filter_map(|f| Some((f, self.field(f.name)?)))
    }

    /// Compiles the multipliers of tag `tag` against resolved parameters
    /// ([`DampingSpec::parse`], then [`ParsedDamping::compile`]).
    pub fn resolve(&self, tag: &str, params: &Resolved) -> Result<TagDamping, BuildError> {
        self.parse(tag)?.compile(tag, params)
    }

    /// The tag's own noise temperature (K) against resolved parameters, `None` when it has
    /// none (the model's `temperature` applies); it must be positive.
    pub fn temperature_value(
        &self,
        tag: &str,
        params: &Resolved,
    ) -> Result<Option<f64>, BuildError> {
        let Some(text) = &self.temperature else {
            return Ok(None);
        };
        let which = context(tag, "temperature");
        let expr = parse(text).map_err(|e| BuildError::Expression {
            context: which.clone(),
            message: e.to_string(),
        })?;
        let compiled = expr
            .compile(&|s: &str| params.get(s).ok().map(Slot::Const))
            .map_err(|e| BuildError::Expression {
                context: which.clone(),
                message: e.to_string(),
            })?;
        // every symbol is a parameter's value, so nothing is read; NaN is refused below
        let value: f64 = compiled.eval(&[]).unwrap_or(f64::NAN);
        DAMPING_TEMPERATURE
            .check(value)
            .map_err(|message| BuildError::Invalid {
                item: format!("damping of tag '{tag}'"),
                message,
            })?;
        Ok(Some(value))
    }

    /// Parses the multipliers of tag `tag`: ε' (`real`, 1 when absent) and ε'' (the sum of
    /// the parts given, 0 when none is). Which parameters they use is only checked when
    /// they are compiled.
    pub fn parse(&self, tag: &str) -> Result<ParsedDamping, BuildError> {
        let parse_part = |text: &str, which: &str| {
            parse(text).map_err(|e| BuildError::Expression {
                context: context(tag, which),
                message: e.to_string(),
            })
        };
        // every field parsed once, by its own name
        let mut parts: Vec<(&'static Field, Expr)> = Vec::new();
        for (field, text) in self.fields() {
            parts.push((field, parse_part(text, field.name)?));
        }
        Ok(ParsedDamping::from_parts(self.clone(), parts))
    }
}

impl ParsedDamping {
    /// `spec` with its fields already parsed: `parts` holds each field that is set, with
    /// the expression its text parses to, in the order of [`DampingSpec::fields`] (what
    /// [`DampingSpec::parse`] makes; a bundled model stores it so as to parse nothing).
    pub fn from_parts(spec: DampingSpec, parts: Vec<(&'static Field, Expr)>) -> ParsedDamping {
        let part = |name: &str| parts.iter().find(|(f, _)| f.name == name).map(|(_, e)| e);
        let real = part("real").cloned().unwrap_or(Expr::Num(1.0));
        let imag = imaginary_multiplier(
            part("structural"),
            part("viscous"),
            (part("thermoelastic.delta"), part("thermoelastic.tau")),
            part("imag"),
        );
        let mut inputs = real.symbols();
        inputs.extend(imag.symbols());
        inputs.remove("f");
        // the parts with a domain narrower than "finite" that do not depend on f, each
        // checked on its own when compiled (the temperature by `temperature_value`)
        let checked = parts
            .into_iter()
            .filter(|(field, _)| field.domain != Domain::Finite && **field != DAMPING_TEMPERATURE)
            .collect();
        ParsedDamping(Arc::new(Parsed {
            spec,
            real,
            imag,
            checked,
            inputs: inputs.into_iter().collect(),
            first: OnceLock::new(),
        }))
    }
}

/// ε''(f), the sum of the parts given (0 when none is): `structural + viscous·f +
/// Δ ωτ/(1 + (ωτ)²) + imag` with ω = 2π f, a half of the thermoelastic pair that is not
/// given being 0. Built from the parsed parts as the tree the parser makes of
/// `(φ)+(v)*f+(Δ)*(2*pi*f*(τ))/(1+(2*pi*f*(τ))^2)+(imag)` (the sum left-associative), so
/// that it evaluates to the same numbers.
fn imaginary_multiplier(
    structural: Option<&Expr>,
    viscous: Option<&Expr>,
    thermoelastic: (Option<&Expr>, Option<&Expr>),
    imag: Option<&Expr>,
) -> Expr {
    let binary = |op, a: Expr, b: Expr| Expr::Binary(op, Box::new(a), Box::new(b));
    let f = || Expr::Sym("f".into());
    let mut terms: Vec<Expr> = Vec::new();
    terms.extend(structural.cloned());
    terms.extend(viscous.map(|v| binary(BinOp::Mul, v.clone(), f())));
    if thermoelastic.0.is_some() || thermoelastic.1.is_some() {
        let zero = Expr::Num(0.0);
        let delta = thermoelastic.0.unwrap_or(&zero).clone();
        let tau = thermoelastic.1.unwrap_or(&zero).clone();
        // 2*pi*f*(τ): ((2·pi)·f)·τ
        let omega_tau = || {
            let two_pi = binary(BinOp::Mul, Expr::Num(2.0), Expr::Sym("pi".into()));
            binary(BinOp::Mul, binary(BinOp::Mul, two_pi, f()), tau.clone())
        };
        let peak = binary(
            BinOp::Div,
            binary(BinOp::Mul, delta, omega_tau()),
            binary(
                BinOp::Add,
                Expr::Num(1.0),
                binary(BinOp::Pow, omega_tau(), Expr::Num(2.0)),
            ),
        );
        terms.push(peak);
    }
    terms.extend(imag.cloned());
    terms
        .into_iter()
        .reduce(|sum, term| binary(BinOp::Add, sum, term))
        .unwrap_or(Expr::Num(0.0))
}

/// Where a damping expression sits, for error messages.
fn context(tag: &str, which: &str) -> String {
    format!("damping of tag '{tag}' ({which})")
}

/// A [`DampingSpec`] with its multipliers parsed, so that a build only compiles them
/// against the resolved parameters (models keep these in their cached
/// [`Defaults`](crate::Defaults)).
///
/// It also keeps its first compilation, with the values of the parameters it read then,
/// and hands out a copy whenever a later build reads the same values (bit for bit): a
/// model's default damping is then compiled once, and stays so for every case that leaves
/// the parameters it depends on alone. Other values are compiled afresh.
///
/// Clones share one parse (and its kept compilation): a model hands its parsed damping to
/// its defaults by cloning it, which must not copy every expression tree.
#[derive(Clone, Debug)]
pub struct ParsedDamping(Arc<Parsed>);

/// What a [`ParsedDamping`] shares among its clones.
#[derive(Debug)]
struct Parsed {
    spec: DampingSpec,
    real: Expr,
    imag: Expr,
    /// The fields with a domain to check, parsed on their own.
    checked: Vec<(&'static Field, Expr)>,
    /// The parameters the multipliers read (every symbol but `f`), sorted.
    inputs: Vec<String>,
    /// The first compilation: the inputs' values then, and its result.
    first: OnceLock<(Vec<f64>, TagDamping)>,
}

impl ParsedDamping {
    /// The specification this was parsed from (to merge a case's fields into).
    pub fn spec(&self) -> &DampingSpec {
        &self.0.spec
    }

    /// Compiles the multipliers of tag `tag` against resolved parameters: every symbol but
    /// `f` (Hz) must be a numeric parameter, and is folded in as a constant.
    pub fn compile(&self, tag: &str, params: &Resolved) -> Result<TagDamping, BuildError> {
        // None when an input is missing or symbolic: compiling reports it
        let values: Option<Vec<f64>> = self.0.inputs.iter().map(|s| params.get(s).ok()).collect();
        if let (Some(values), Some((first_values, compiled))) = (&values, self.0.first.get())
            && values
                .iter()
                .map(|v| v.to_bits())
                .eq(first_values.iter().map(|v| v.to_bits()))
        {
            return Ok(compiled.clone());
        }
        let compile = |expr: &Expr, which: &str| {
            let slot = |s: &str| {
                if s == "f" {
                    Some(Slot::Var(0))
                } else {
                    params.get(s).ok().map(Slot::Const)
                }
            };
            expr.compile(&slot).map_err(|e| BuildError::Expression {
                context: context(tag, which),
                message: e.to_string(),
            })
        };
        let compiled = TagDamping {
            real: compile(&self.0.real, "real")?,
            imag: compile(&self.0.imag, "imag")?,
        };
        for (field, expr) in &self.0.checked {
            // NaN (a part that reads f) is refused by the check
            let value = compile(expr, field.name)?.eval(&[]).unwrap_or(f64::NAN);
            field.check(value).map_err(|message| BuildError::Invalid {
                item: format!("damping of tag '{tag}'"),
                message,
            })?;
        }
        if let Some(values) = values {
            // a concurrent build may have set it first, with its own values: either is right
            let _ = self.0.first.set((values, compiled.clone()));
        }
        Ok(compiled)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pendkit_params::ParamSet;

    fn params() -> Resolved {
        let mut p = ParamSet::new();
        p.define("delta", "1.945745e-5").unwrap();
        p.define("tau", "1.450933e-2").unwrap();
        p.define("phi", "1e-7").unwrap();
        p.resolve().unwrap()
    }

    #[test]
    fn thermoelastic_peak_matches_the_oracle_table() {
        // docs/reference-values.md §7, silica fibre with the stress term: Δ = 1.945745e-5,
        // τ = 1.450933e-2 s; φ_TE(1, 10, 100, 500 Hz) printed to 7 digits.
        let spec = DampingSpec::thermoelastic("delta", "tau");
        let d = spec.resolve("t", &params()).unwrap();
        for (f, printed) in [
            (1.0, 1.759213e-6),
            (10.0, 9.687251e-6),
            (100.0, 2.108941e-6),
            (500.0, 4.266579e-7),
        ] {
            let (re, im) = d.at(f);
            assert_eq!(re, 1.0);
            assert!((im - printed).abs() <= 0.5e-6 * printed, "{f} Hz: {im}");
        }
    }

    #[test]
    fn parts_add_and_fields_merge() {
        // §6: φ_w(ω) = φ + Δ ωτ/(1 + ω²τ²) = 9.787251e-6 at 10 Hz with φ = 1e-7.
        let mut spec = DampingSpec::structural("phi");
        spec.merge(&DampingSpec::thermoelastic("delta", "tau"));
        let (_, im) = spec.resolve("t", &params()).unwrap().at(10.0);
        assert!((im - 9.787251e-6).abs() <= 0.5e-12);
        spec.set_field("viscous", "2e-3").unwrap();
        spec.set_field("real", "1 + 0*f").unwrap();
        let (re, im2) = spec.resolve("t", &params()).unwrap().at(10.0);
        assert_eq!(re, 1.0);
        assert!((im2 - im - 2e-2).abs() < 1e-15);
        assert!(spec.set_field("loss", "1").is_err());
        let bad = DampingSpec::structural("nosuch");
        assert!(
            bad.resolve("t", &params())
                .unwrap_err()
                .to_string()
                .contains("nosuch")
        );
    }

    /// Every field of the schema has its place: set by its name, read back by its name,
    /// and no other field changes.
    #[test]
    fn every_schema_field_is_set_and_read_by_its_name() {
        for (k, field) in DAMPING_FIELDS.iter().enumerate() {
            let mut spec = DampingSpec::default();
            spec.set_field(field.name, &format!("{k}")).unwrap();
            let set: Vec<_> = spec
                .fields()
                .map(|(f, t)| (f.name, t.to_string()))
                .collect();
            assert_eq!(set, vec![(field.name, format!("{k}"))]);
        }
        assert!(DampingSpec::default().set_field("phi", "1").is_err());
    }

    /// ε'' built from the parsed parts is the tree the parser makes of the parts written
    /// out as one expression (the text the multiplier was parsed from before): the same
    /// numbers, to the last bit.
    #[test]
    fn the_imaginary_multiplier_is_the_parsers_tree_of_its_parts() {
        let (s, v, d, t, i) = ("phi*(1+2)", "-3e-3", "delta^2", "tau/2", "1e-7*(1+f/100)");
        let whole = format!("({s})+({v})*f+({d})*(2*pi*f*({t}))/(1+(2*pi*f*({t}))^2)+({i})");
        let mut spec = DampingSpec::default();
        for (field, text) in [
            ("structural", s),
            ("viscous", v),
            ("thermoelastic.delta", d),
            ("thermoelastic.tau", t),
            ("imag", i),
        ] {
            spec.set_field(field, text).unwrap();
        }
        assert_eq!(spec.parse("t").unwrap().0.imag, parse(&whole).unwrap());
        // one half of the pair: the other is 0; no part at all: 0
        let half = DampingSpec {
            thermoelastic_tau: Some(t.into()),
            ..Default::default()
        };
        let written = format!("(0)*(2*pi*f*({t}))/(1+(2*pi*f*({t}))^2)");
        assert_eq!(half.parse("t").unwrap().0.imag, parse(&written).unwrap());
        assert_eq!(
            DampingSpec::default().parse("t").unwrap().0.imag,
            Expr::Num(0.0)
        );
        assert_eq!(
            DampingSpec::default().parse("t").unwrap().0.real,
            Expr::Num(1.0)
        );
    }

    #[test]
    fn a_kept_compilation_is_reused_only_for_the_same_values() {
        // φ(f) = phi + viscous 2e-3 f: the first compilation (phi = 1e-7) is kept; other
        // values of phi must compile afresh, and the first values reuse the kept one.
        let spec = DampingSpec {
            structural: Some("phi".into()),
            viscous: Some("2e-3".into()),
            ..Default::default()
        };
        let parsed = spec.parse("t").unwrap();
        let with_phi = |phi: f64| {
            let mut p = ParamSet::new();
            p.define_value("phi", phi).unwrap();
            p.define_value("unrelated", phi).unwrap();
            p.resolve().unwrap()
        };
        for phi in [1e-7, 3e-5, 1e-7, -0.0, 0.0, 1e-7] {
            let (re, im) = parsed.compile("t", &with_phi(phi)).unwrap().at(10.0);
            assert_eq!((re, im), (1.0, phi + 2e-2), "phi = {phi}");
        }
        // a missing parameter is still reported after a kept compilation exists
        let e = parsed.compile("t", &ParamSet::new().resolve().unwrap());
        assert!(e.unwrap_err().to_string().contains("phi"));
    }
}
