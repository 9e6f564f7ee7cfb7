//! `hdi validate` rows of the ISBL contact model (docs/contact.md): computed now with the
//! same model the contact stage and the dynamics use.

use super::pipeline::{self, MeasuredSummits};
use super::{Basis, Class, Origin, Row, Tolerance};
use crate::artefacts::contact::friction_law_name;
use crate::contact::isbl::summits::{fit_two_point, TwoPointTarget, FIG_2_11_NOMINAL_AREA};
use crate::contact::isbl::{FrictionLaw, IsblModel, IsblParams, SummitDistribution};
use std::path::Path;

/// The friction laws other than the default whose values the friction rows also carry
/// (docs/model-form.md, "Friction").
const OTHER_FRICTION_LAWS: [FrictionLaw; 2] =
    [FrictionLaw::SeedPowerElastic, FrictionLaw::KeStatic];

/// `model` with friction law `law` (the inputs are the validated ones, so this cannot fail).
fn with_law(model: &IsblModel, law: FrictionLaw) -> Option<IsblModel> {
    IsblModel::new(IsblParams {
        friction_law: law,
        ..*model.params()
    })
    .ok()
}

/// `friction_law = NAME`.
fn law_variant(law: FrictionLaw) -> String {
    format!("friction_law = {}", friction_law_name(law))
}

/// A row with borrowed text, built by name (the MTL rows use it too).
pub(super) struct R<'a> {
    pub(super) source: &'a str,
    pub(super) quantity: &'a str,
    pub(super) unit: &'a str,
    pub(super) target: f64,
    pub(super) ours: f64,
    pub(super) tolerance: Tolerance,
    pub(super) reproducible: bool,
    pub(super) variant: &'a str,
    pub(super) note: &'a str,
}

impl R<'_> {
    /// The typed row: `source` is "TABLE #TAG [REFERENCE]"; the id is `isbl-TAG` (the
    /// ISBL table's row tag; the area makes repeats unique), the reference the bracketed part
    /// with "dissertation" read as the dissertation. Reproducible rows are class G (closed forms and
    /// an independent implementation), the others class D (the dissertation's number depends on
    /// inputs or readings the text does not give; the note says which).
    pub(super) fn row(self) -> Row {
        let tag = self
            .source
            .split_once('#')
            .map(|(_, t)| {
                t.split(|c: char| c.is_whitespace() || c == '/')
                    .next()
                    .unwrap_or("")
                    .to_string()
            })
            .filter(|t| !t.is_empty());
        let reference = self
            .source
            .split_once('[')
            .map(|(_, r)| r.trim_end_matches(']').to_string())
            .unwrap_or_else(|| "independent reference table (docs/contact.md)".into())
            .replace("seed", "dissertation")
            .replace("derived", "derived in closed form");
        Row::new(
            &tag.map_or(String::new(), |t| format!("isbl-{t}")),
            if self.reproducible {
                Class::G
            } else {
                Class::D
            },
            self.quantity,
            self.unit,
            self.target,
            self.ours,
            self.tolerance,
        )
        .reference(&reference)
        .variant(self.variant)
        .note(self.note)
    }
}

fn failed(quantity: &str, why: String) -> Row {
    Row::new(
        "",
        Class::G,
        quantity,
        "-",
        f64::NAN,
        f64::NAN,
        Tolerance::Absolute(0.0),
    )
    .variant("-")
    .note(&why)
}

const VARIANT: &str = "ISBL, summit_distribution surface (d = h), junction-shear friction";

/// One summit distribution other than the rows' own (`surface`), for [`Row::with_variant`]
/// (docs/model-form.md, "Summit heights").
pub(super) struct SummitVariant {
    /// `summit_distribution = …`.
    pub name: String,
    /// The interface with this distribution; `None` if it could not be built (the value is
    /// then NaN and `inputs` says why).
    pub params: Option<IsblParams>,
    pub inputs: String,
    pub origin: Origin,
}

/// `mccool`, `fig_2_11` (fitted on `base` itself with Fig. 2.11's force on 55 µm², as a
/// `[contact]` instance of `base` would fit it) and, when the pipeline's surfaces have run,
/// `measured`, on the interface `base`.
pub(super) fn summit_variants(
    base: &IsblParams,
    measured: Option<&MeasuredSummits>,
) -> Vec<SummitVariant> {
    let with = |d: SummitDistribution| IsblParams {
        summits: d,
        ..*base
    };
    let mut v = vec![SummitVariant {
        name: "summit_distribution = mccool".into(),
        params: Some(with(SummitDistribution::McCool)),
        inputs: "McCool's summit relations from β = σRη".into(),
        origin: Origin::Computed,
    }];
    let fit = fit_two_point(base, &TwoPointTarget::fig_2_11(FIG_2_11_NOMINAL_AREA));
    v.push(SummitVariant {
        name: "summit_distribution = fig_2_11".into(),
        params: fit.as_ref().ok().map(|f| with(f.distribution())),
        inputs: match &fit {
            Ok(f) => format!(
                "σ_s, y_s fitted to Fig. 2.11 (7.30 µN at h* = 3 on 55 µm², 3 % of P(2.5)): σ_s/σ = {:.4}, y_s/σ = {:.4}",
                f.sigma_ratio, f.offset_ratio
            ),
            Err(e) => format!("the Fig. 2.11 fit failed: {e}"),
        },
        origin: Origin::Computed,
    });
    if let Some(m) = measured {
        v.push(SummitVariant {
            name: "summit_distribution = measured".into(),
            params: Some(with(SummitDistribution::Given {
                sigma_ratio: m.sigma_ratio,
                offset_ratio: m.offset_ratio,
            })),
            inputs: m.inputs.clone(),
            origin: m.origin.clone(),
        });
    }
    v
}

/// `row` with `value(params)` under every summit variant.
fn with_summit_variants(
    row: Row,
    variants: &[SummitVariant],
    value: impl Fn(&IsblParams) -> Option<f64>,
) -> Row {
    variants.iter().fold(row, |row, v| {
        let x = v.params.as_ref().and_then(&value).unwrap_or(f64::NAN);
        row.with_variant(&v.name, x, &v.inputs, v.origin.clone())
    })
}

/// The three §10 parameter sets the rows evaluate.
struct Sets {
    initial: IsblModel,
    improved: IsblModel,
    mtl: IsblModel,
}

/// The ISBL state at the dimensionless separation `h_star` (in units of σ).
fn at(
    m: &IsblModel,
    h_star: f64,
) -> Result<crate::contact::isbl::IsblPoint, crate::contact::ContactError> {
    m.at(h_star * m.params().sigma)
}

/// The ISBL rows. `config`: the pipeline whose measured surfaces give the `measured` summit
/// variant (the rows themselves need no pipeline).
pub fn rows(config: Option<&Path>) -> Vec<Row> {
    let sets = match (
        IsblModel::new(IsblParams::initial_2dof()),
        IsblModel::new(IsblParams::improved_2dof()),
        IsblModel::new(IsblParams::mtl_table_3_2()),
    ) {
        (Ok(initial), Ok(improved), Ok(mtl)) => Sets {
            initial,
            improved,
            mtl,
        },
        _ => {
            return vec![failed(
                "ISBL parameter sets",
                "a parameter set did not validate".into(),
            )]
        }
    };
    let measured = pipeline::open(config)
        .zip(config)
        .and_then(|(cache, c)| pipeline::measured_summits(c, &cache));
    let initial_variants = summit_variants(sets.initial.params(), measured.as_ref());
    let improved_variants = summit_variants(sets.improved.params(), measured.as_ref());
    let mut rows = derived_rows(&sets.initial);
    rows.extend(initial_curve_rows(&sets.initial, &initial_variants));
    rows.push(adhesion_12nm_row(&sets.improved, &improved_variants));
    rows.extend(static_contact_force_rows(
        &sets,
        &initial_variants,
        &improved_variants,
    ));
    rows.extend(sphere_rows());
    rows.extend(reference_table_rows(&sets));
    super::assign_ids("isbl", &mut rows);
    // ψ = 0.52 is the dynamics area's `dyn-14` (one row per printed number).
    rows.retain(|r| r.id != "isbl-3");
    for r in &mut rows {
        if r.basis == Basis::Unstated {
            r.basis = basis_of(&r.id);
        }
        if matches!(r.basis, Basis::ByConstruction { .. }) {
            r.class = Class::C;
        }
    }
    rows
}

/// The ledger of the ISBL rows (docs/validation.md): which targets the dissertation prints,
/// which come from an independent evaluation of the printed equations, and which recover an
/// input that was back-solved from them.
fn basis_of(id: &str) -> Basis {
    let printed = |at: &str| Basis::Published { at: at.into() };
    let derived = |how: &str| Basis::Derived { how: how.into() };
    let built = |what: &str| Basis::ByConstruction { what: what.into() };
    match id {
        "isbl-1" | "isbl-2" => {
            derived("closed form of App. A with E = 280 GPa, ν = 0.25, H = 13 GPa")
        }
        "isbl-1a" => derived(
            "the independent reference implementation's P(3σ) per unit area, initial set (the \
             dissertation prints 7.30 µN on an area it does not state)",
        ),
        "isbl-1a.2" => built("the 66.6 µm² area was back-solved from 7.30 µN with this P(3σ)"),
        "isbl-1b" => {
            printed("dissertation §2.2.1, Fig. 2.11 (\"only 3 % of the value of P at h* = 2.5\")")
        }
        "isbl-1c" => derived(
            "the independent reference implementation's F_s(6σ)/F_s(0); the dissertation says \
             only that adhesion is negligible from h* = 6 (§2.2.1, Fig. 2.11)",
        ),
        "isbl-2c" => built("Δγ = 0.06 N/m was back-solved from this 0.98 mN (docs/contact.md)"),
        "isbl-2a" | "isbl-2b" => {
            printed("dissertation §2.2.2 (12 nm: F_c 1.63 mN, μ 1.49, A_r 0.36 µm²)")
        }
        "isbl-2a.2" | "isbl-2b.2" => {
            printed("dissertation §2.1.3 (11 nm: F_c ≈ 1 mN, A_r 2.7 µm², 438/359 MPa)")
        }
        "isbl-3.2" | "isbl-4" | "isbl-4.3" => printed("dissertation §3.1 (DLC sphere on DLC)"),
        "isbl-4.2" | "isbl-4.4" => built(
            "the junction-shear friction law was chosen because it meets these two numbers \
             (docs/contact.md): they selected it, so they cannot confirm it",
        ),
        _ => derived("the independent reference implementation's ISBL curves (docs/contact.md)"),
    }
}

/// §10 derived quantities of the initial set: E*, the plasticity index ψ (Ch. 2.1), ω_c.
fn derived_rows(initial: &IsblModel) -> Vec<Row> {
    let d = initial.derived();
    vec![
        R {
            source: "contact-isbl §10 [derived]",
            quantity: "composite modulus E* (DLC/DLC, ν = 0.25)",
            unit: "GPa",
            target: 149.3,
            ours: d.composite_modulus / 1e9,
            tolerance: Tolerance::Absolute(0.05),
            reproducible: true,
            variant: VARIANT,
            note: "",
        }
        .row(),
        R {
            source: "contact-isbl §9 #3 [dissertation Ch. 2.1]",
            quantity: "plasticity index ψ, Ch. 2 interface",
            unit: "1",
            target: 0.52,
            ours: d.plasticity_index,
            tolerance: Tolerance::Absolute(0.005),
            reproducible: true,
            variant: VARIANT,
            note: "fixes ν ∈ [0.25, 0.27]",
        }
        .row(),
        R {
            source: "contact-isbl §10 [derived]",
            quantity: "critical interference ω_c",
            unit: "nm",
            target: 2.49,
            ours: d.critical_interference * 1e9,
            tolerance: Tolerance::Absolute(0.005),
            reproducible: true,
            variant: VARIANT,
            note: "",
        }
        .row(),
    ]
}

/// #1a–#1c: the initial set's pressure and adhesion curves (Ch. 2.2, Fig. 2.11).
fn initial_curve_rows(initial: &IsblModel, variants: &[SummitVariant]) -> Vec<Row> {
    let pressure = |p: &IsblParams, h_star: f64| {
        IsblModel::new(*p)
            .and_then(|m| m.contact_pressure(h_star * p.sigma))
            .ok()
    };
    let (p3, p25, p6, p0) = match (
        at(initial, 3.0),
        at(initial, 2.5),
        at(initial, 6.0),
        at(initial, 0.0),
    ) {
        (Ok(p3), Ok(p25), Ok(p6), Ok(p0)) => (p3, p25, p6, p0),
        _ => return vec![failed("initial set curves", "evaluation failed".into())],
    };
    vec![
        R {
            source: "contact-isbl §9 #1a [dissertation Ch. 2.2, Fig. 2.11]",
            quantity: "P(h* = 3) per unit nominal area, initial set",
            unit: "Pa",
            target: 1.097e5,
            ours: p3.contact_pressure,
            tolerance: Tolerance::Relative(0.01),
            reproducible: true,
            variant: VARIANT,
            note: "",
        }
        .row(),
        R {
            source: "contact-isbl §9 #1a [dissertation: 7.30 μN]",
            quantity: "P(h* = 3) on A_n = 66.6 μm², initial set",
            unit: "μN",
            target: 7.30,
            ours: p3.contact_pressure * 66.6e-12 * 1e6,
            tolerance: Tolerance::Relative(0.01),
            reproducible: true,
            variant: VARIANT,
            note: "",
        }
        .row()
        .class(Class::C)
        .note(
            "consistency check, not a reproduction: the figure's A_n is not stated and 66.6 μm² \
             is the area back-solved from 7.30 μN with this P(3); 62–68 μm² (Ch. 2 areas) give \
             6.8–7.5 μN",
        ),
        with_summit_variants(
            R {
                source: "contact-isbl §9 #1b [dissertation §2.2.1, Fig. 2.11(b)]",
                quantity: "P(3)/P(2.5): \"7.30 μN is about 3 % of P at h* = 2.5\"",
                unit: "1",
                target: 0.03,
                ours: p3.contact_pressure / p25.contact_pressure,
                tolerance: Tolerance::Relative(0.1),
                reproducible: false,
                variant: VARIANT,
                note: "not reproduced with the summits at the surface heights' statistics \
                       (0.18; 3 % is reached at h* = 1.90): the dissertation's curve falls 6× \
                       faster between 2.5σ and 3σ. A summit distribution narrower and higher \
                       than the surface heights gives it (σ_s ≈ 0.35σ, y_s ≈ 2.2σ: the \
                       fig_2_11 variant, fitted to this number; docs/model-form.md, \
                       \"Summit heights\")",
            }
            .row()
            .published("dissertation §2.2.1, Fig. 2.11(b)"),
            variants,
            |p| Some(pressure(p, 3.0)? / pressure(p, 2.5)?),
        ),
        with_summit_variants(
            R {
                source: "contact-isbl §9 #1c [dissertation: adhesion negligible for h* ≥ 6]",
                quantity: "F_s(6)/F_s(0), initial set (σ = 0.87 nm)",
                unit: "1",
                target: 0.008,
                ours: p6.adhesion / p0.adhesion,
                tolerance: Tolerance::Absolute(0.001),
                reproducible: true,
                variant: VARIANT,
                note: "",
            }
            .row()
            .derived(
                "F_s(6)/F_s(0) of the independent reference implementation on the initial set; \
                 the dissertation states only that adhesion is negligible from h* = 6 (§2.2.1, \
                 Fig. 2.11(c))",
            ),
            variants,
            |p| {
                let m = IsblModel::new(*p).ok()?;
                Some(m.at(6.0 * p.sigma).ok()?.adhesion / m.at(0.0).ok()?.adhesion)
            },
        ),
    ]
}

/// #2c: adhesion at the 12 nm clearance (h_c = 1.16 nm) on A_n = 55 μm², improved set.
fn adhesion_12nm_row(improved: &IsblModel, variants: &[SummitVariant]) -> Row {
    match improved.at(1.16e-9) {
        Ok(p) => with_summit_variants(
            R {
                source: "contact-isbl §9 #2c [dissertation Ch. 2.2.2]",
                quantity: "adhesion at 12 nm actuation (h = 1.16 nm, A_n = 55 μm²)",
                unit: "mN",
                target: 0.98,
                ours: p.adhesion * 55e-12 * 1e3,
                tolerance: Tolerance::Relative(0.05),
                reproducible: true,
                variant: "ISBL improved set, Δγ = 0.06 N/m (back-solved), ε = 0.3 nm",
                note: "",
            }
            .row()
            .by_construction(
                "Δγ = 0.06 N/m was back-solved from this 0.98 mN (dissertation §2.2.2, the 12 nm \
                 adhesion; docs/contact.md)",
            ),
            variants,
            |p| {
                IsblModel::new(*p)
                    .and_then(|m| m.at(1.16e-9))
                    .ok()
                    .map(|q| q.adhesion * 55e-12 * 1e3)
            },
        ),
        Err(e) => failed("adhesion at 12 nm", e.to_string()),
    }
}

/// One Ch. 2 operating point whose dynamic contact force #2a/#2b/#2d read statically.
struct ForcePoint<'a> {
    label: &'a str,
    model: &'a IsblModel,
    /// Nominal contact area A_n (m²).
    area: f64,
    /// Dynamic contact force F_c (N).
    force: f64,
    mu_target: f64,
    real_area_target: f64,
    mu_reproducible: bool,
    /// Where the dissertation prints μ and A_r at this point.
    published_at: &'a str,
    /// The point under the other summit distributions.
    variants: &'a [SummitVariant],
    note_mu: &'a str,
    note_real_area: &'a str,
}

/// #2a/#2b/#2d: the dynamic contact force read statically, at the h where P·A_n = F_c.
fn static_contact_force_rows(
    sets: &Sets,
    initial_variants: &[SummitVariant],
    improved_variants: &[SummitVariant],
) -> Vec<Row> {
    let points = [
        ForcePoint {
            label: "12 nm, improved set (A_n = 55 μm², F_c = 1.63 mN)",
            model: &sets.improved,
            area: 55e-12,
            force: 1.63e-3,
            mu_target: 1.49,
            real_area_target: 0.36,
            mu_reproducible: false,
            published_at: "dissertation §2.2.2, Figs. 2.13–2.14 (12 nm: F_c 1.63 mN, μ 1.49, \
                           A_r 0.36 μm²; A_n 55 μm², §2.2.1)",
            variants: improved_variants,
            note_mu:
                "−14 %: the dissertation's μ lies inside the model's μ(h) range (1.65 at the mean clearance)",
            note_real_area:
                "the dissertation's dynamic F_c (a linearised spring) is not P(h) at the mean separation",
        },
        ForcePoint {
            label: "11 nm, initial set (A_n = 62 μm², F_c ≈ 1 mN)",
            model: &sets.initial,
            area: 62e-12,
            force: 1e-3,
            mu_target: 1.2,
            real_area_target: 2.7,
            mu_reproducible: true,
            published_at: "dissertation §2.1.3 (11 nm: F_c ≈ 1 mN, A_r 2.7 μm² of A_n 62 μm², \
                           μ ≈ 1.2 from 438/359 MPa)",
            variants: initial_variants,
            note_mu: "",
            note_real_area:
                "A_r = 2.72 μm² needs h* = 0.21 where P = 8.1 mN: the dynamic-vs-static caveat of #2b",
        },
    ];
    let mut rows = Vec::new();
    for pt in points {
        let label = pt.label;
        let at_load = |params: &IsblParams| {
            IsblModel::new(*params)
                .and_then(|m| separation_for_load(&m, pt.force / pt.area))
                .ok()
        };
        match separation_for_load(pt.model, pt.force / pt.area) {
            Ok(p) => {
                // The same separation under the other laws (P does not depend on the law).
                let mut mu = R {
                    source: "contact-isbl §9 #2a/#2d [dissertation Ch. 2]",
                    quantity: &format!("μ = Q/P at P·A_n = F_c, {label}"),
                    unit: "1",
                    target: pt.mu_target,
                    ours: p.friction_stress / p.contact_pressure,
                    tolerance: Tolerance::Relative(0.10),
                    reproducible: pt.mu_reproducible,
                    variant: VARIANT,
                    note: pt.note_mu,
                }
                .row()
                .published(pt.published_at);
                for law in OTHER_FRICTION_LAWS {
                    let value = with_law(pt.model, law)
                        .and_then(|m| m.at(p.separation).ok())
                        .map_or(f64::NAN, |q| q.friction_stress / q.contact_pressure);
                    mu = mu.with_variant(
                        &law_variant(law),
                        value,
                        "the same h (P·A_n = F_c); P does not depend on the law",
                        Origin::Computed,
                    );
                }
                rows.push(with_summit_variants(mu, pt.variants, |v| {
                    at_load(v).map(|q| q.friction_stress / q.contact_pressure)
                }));
                rows.push(with_summit_variants(
                    R {
                        source: "contact-isbl §9 #2b/#2d [dissertation Ch. 2]",
                        quantity: &format!("real area at P·A_n = F_c, {label}"),
                        unit: "μm²",
                        target: pt.real_area_target,
                        ours: p.real_area_fraction * pt.area * 1e12,
                        tolerance: Tolerance::Relative(0.10),
                        reproducible: false,
                        variant: VARIANT,
                        note: pt.note_real_area,
                    }
                    .row()
                    .published(pt.published_at),
                    pt.variants,
                    |v| at_load(v).map(|q| q.real_area_fraction * pt.area * 1e12),
                ));
            }
            Err(e) => rows.push(failed(label, e.to_string())),
        }
    }
    rows
}

/// One interference of the Ch. 3.1 sphere with its load and friction targets (μN).
struct SpherePoint {
    /// Interference ω (m).
    omega: f64,
    load_target: f64,
    friction_target: f64,
    load_reproducible: bool,
}

/// #4: the Ch. 3.1 DLC sphere on DLC (E = 180 GPa, ν = 0.24, H = 18 GPa, R = 102 μm).
fn sphere_rows() -> Vec<Row> {
    let sphere = IsblModel::new(IsblParams {
        summit_radius: 102e-6,
        slider_modulus: 180e9,
        disk_modulus: 180e9,
        slider_poisson: 0.24,
        disk_poisson: 0.24,
        yielding_poisson: 0.24,
        hardness: 18e9,
        ..IsblParams::initial_2dof()
    });
    let sphere = match sphere {
        Ok(sphere) => sphere,
        Err(e) => return vec![failed("Ch. 3.1 sphere", e.to_string())],
    };
    let mut rows = vec![R {
        source: "contact-isbl §5 [dissertation Ch. 3.1]",
        quantity: "reduced modulus E*, DLC sphere on DLC",
        unit: "GPa",
        target: 95.5,
        ours: sphere.derived().composite_modulus / 1e9,
        tolerance: Tolerance::Absolute(0.05),
        reproducible: true,
        variant: "E = 180 GPa, ν = 0.24",
        note: "",
    }
    .row()];
    let points = [
        SpherePoint {
            omega: 0.1e-9,
            load_target: 1.5,
            friction_target: 120.0,
            load_reproducible: false,
        },
        SpherePoint {
            omega: 1e-9,
            load_target: 40.0,
            friction_target: 1120.0,
            load_reproducible: true,
        },
    ];
    for pt in points {
        let omega = pt.omega;
        match sphere.asperity_at(omega) {
            Ok(a) => {
                rows.push(
                    R {
                        source: "contact-isbl §9 #4 [dissertation Ch. 3.1]",
                        quantity: &format!("sphere load at ω = {} nm", omega * 1e9),
                        unit: "μN",
                        target: pt.load_target,
                        ours: a.load * 1e6,
                        tolerance: Tolerance::Relative(0.03),
                        reproducible: pt.load_reproducible,
                        variant: "Hertz (KE elastic)",
                        note: if pt.load_reproducible {
                            ""
                        } else {
                            "Hertz gives 1.29 μN; the dissertation's 1.5 μN is 14 % above \
                             (likely rounding in the dissertation)"
                        },
                    }
                    .row(),
                );
                let mut friction = R {
                    source: "contact-isbl §9 #4 [dissertation Ch. 3.1]",
                    quantity: &format!("sphere static friction at ω = {} nm", omega * 1e9),
                    unit: "μN",
                    target: pt.friction_target,
                    ours: a.friction * 1e6,
                    tolerance: Tolerance::Relative(0.10),
                    reproducible: true,
                    variant: "junction shear τ_s = H/(2.8√3)",
                    note: "",
                }
                .row()
                .reference("dissertation §3.1")
                // The junction-shear law was chosen because it meets these two numbers
                // (docs/contact.md), and the other two laws are back-solved from them: no
                // law's value here can confirm it.
                .by_construction(
                    "every friction law was chosen on or back-solved from these two numbers \
                     (docs/contact.md)",
                );
                for law in OTHER_FRICTION_LAWS {
                    let value = with_law(&sphere, law)
                        .and_then(|m| m.asperity_at(omega).ok())
                        .map_or(f64::NAN, |a| a.friction * 1e6);
                    let inputs = match law {
                        // The power law is back-solved from these two numbers.
                        FrictionLaw::SeedPowerElastic => {
                            "by construction: the law is back-solved from these two values"
                        }
                        _ => {
                            "adhesion-augmented load with Δγ = 0.06 N/m, ε = 0.3 nm (Ch. 2's; \
                             Ch. 3.1 names none): without adhesion the law gives the values \
                             of the Ch. 3.1 power law it is built on (by construction)"
                        }
                    };
                    friction =
                        friction.with_variant(&law_variant(law), value, inputs, Origin::Computed);
                }
                rows.push(friction);
            }
            Err(e) => rows.push(failed("Ch. 3.1 sphere", e.to_string())),
        }
    }
    rows
}

/// The worst relative deviation of P, k_c, A_r, Q, F_s from a §9 reference table.
fn worst_deviation(model: &IsblModel, table: &[[f64; 6]]) -> f64 {
    table
        .iter()
        .map(|r| match at(model, r[0]) {
            Ok(p) => {
                let ours = [
                    p.contact_pressure,
                    p.contact_stiffness,
                    p.real_area_fraction,
                    p.friction_stress,
                    p.adhesion,
                ];
                ours.iter()
                    .zip(&r[1..])
                    .map(|(o, t)| ((o - t) / t).abs())
                    .fold(0.0, f64::max)
            }
            Err(_) => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}

/// The reference curves of §9 (independent implementation), all three sets.
fn reference_table_rows(sets: &Sets) -> Vec<Row> {
    [
        ("initial 2-DOF", &sets.initial, REF_INITIAL),
        ("improved 2-DOF / 3-DOF", &sets.improved, REF_IMPROVED),
        ("Table 3.2 (MTL)", &sets.mtl, REF_MTL),
    ]
    .into_iter()
    .map(|(name, model, table)| {
        R {
            source: "contact-isbl §9 reference table",
            quantity: &format!(
                "{name}: worst relative deviation of P, k_c, A_r, Q, F_s (h* = 0…6)"
            ),
            unit: "1",
            target: 0.0,
            ours: worst_deviation(model, table),
            tolerance: Tolerance::Absolute(1e-6),
            reproducible: true,
            variant: VARIANT,
            note: "printed to 7 digits: the bound is their rounding",
        }
        .row()
    })
    .collect()
}

/// The ISBL state where the contact pressure equals `pressure` (P decreases with h: bisection
/// in h* ∈ [−4, 10]).
fn separation_for_load(
    model: &IsblModel,
    pressure: f64,
) -> Result<crate::contact::isbl::IsblPoint, crate::contact::ContactError> {
    let sigma = model.params().sigma;
    let (mut lo, mut hi) = (-4.0 * sigma, 10.0 * sigma);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if model.at(mid)?.contact_pressure > pressure {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    model.at(0.5 * (lo + hi))
}

/// §9 reference rows: h*, P (Pa), k_c (Pa/m), A_r/A_n, Q (Pa), F_s const (Pa).
/// (The Table 3.2 set uses the variable surface energy: its F_s column is "F_s var".)
const REF_INITIAL: &[[f64; 6]] = &[
    [
        0.0,
        1.787644e8,
        2.948524e17,
        5.808404e-2,
        1.556975e8,
        2.268814e7,
    ],
    [
        1.0,
        3.144019e7,
        7.462058e16,
        1.214034e-2,
        3.254284e7,
        1.770540e7,
    ],
    [
        2.0,
        2.762091e6,
        8.939788e15,
        1.237364e-3,
        3.316821e6,
        1.070633e7,
    ],
    [
        3.0,
        1.096684e5,
        4.597661e14,
        5.569261e-5,
        1.492871e5,
        4.118073e6,
    ],
    [
        4.0,
        1.844296e3,
        9.603362e12,
        1.041303e-6,
        2.791270e3,
        1.111804e6,
    ],
    [
        6.0,
        3.408268e-2,
        2.500619e8,
        2.278644e-11,
        6.108031e-2,
        1.784769e5,
    ],
];
const REF_IMPROVED: &[[f64; 6]] = &[
    [
        0.0,
        7.783863e7,
        2.232361e17,
        3.341335e-2,
        8.956631e7,
        2.216281e7,
    ],
    [
        1.0,
        1.369682e7,
        5.655907e16,
        6.978076e-3,
        1.870511e7,
        2.039026e7,
    ],
    [
        2.0,
        1.203397e6,
        6.777096e15,
        7.111376e-4,
        1.906243e6,
        1.857828e7,
    ],
    [
        3.0,
        4.778119e4,
        3.485471e14,
        3.200728e-5,
        8.579727e4,
        1.387559e7,
    ],
    [
        4.0,
        8.035387e2,
        7.280288e12,
        5.984501e-7,
        1.604178e3,
        7.173564e6,
    ],
    [
        6.0,
        1.484943e-2,
        1.895715e8,
        1.309566e-11,
        3.510363e-2,
        1.055160e6,
    ],
];
const REF_MTL: &[[f64; 6]] = &[
    [
        0.0,
        6.225574e7,
        1.088691e17,
        6.276580e-2,
        1.941313e8,
        2.551295e7,
    ],
    [
        1.0,
        1.095479e7,
        2.758308e16,
        1.310807e-2,
        4.054257e7,
        1.547513e7,
    ],
    [
        2.0,
        9.624836e5,
        3.305096e15,
        1.335847e-3,
        4.131704e6,
        7.095816e6,
    ],
    [
        3.0,
        3.821565e4,
        1.699816e14,
        6.012454e-5,
        1.859621e5,
        2.323256e6,
    ],
    [
        4.0,
        6.426746e2,
        3.550496e12,
        1.124167e-6,
        3.476991e3,
        5.870508e5,
    ],
    [
        6.0,
        1.187666e-2,
        9.245139e7,
        2.459972e-11,
        7.608567e-2,
        8.712156e4,
    ],
];
