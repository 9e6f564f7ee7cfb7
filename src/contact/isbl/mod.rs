//! ISBL rough-surface contact model (App. A.1; docs/contact.md): Greenwood–Williamson summit
//! statistics, Kogut–Etsion elastic-plastic asperities, junction-shear static friction, and
//! adhesion from non-contacting (LJ), lubricant-contacting (SBL) and solid-contacting (DMT)
//! summits, with a constant or thickness-dependent surface energy.
//!
//! All curves are per unit nominal area (`A_n = 1 m²`) as functions of the **solid**
//! separation `h` (smooth flat ↔ mean plane of the DLC surface heights); callers multiply by
//! `A_n`. Stiffnesses come from differentiating the Gaussian density under the integral
//! (docs/contact.md), never from finite differences, so they are as accurate as the curves.
//!
//! Pure functions, SI units, no I/O.

pub mod asperity;
mod quadrature;
pub mod summits;

#[cfg(test)]
mod tests;

use crate::contact::ContactError;
use asperity::{
    adhesion_factor_elastic_fast, ke_area_ratio_in, ke_load_ratio_in, ke_static_friction_ratio_in,
    seed_power_friction_ratio, KeRegime,
};
use std::f64::consts::PI;

/// The Gaussian distribution of summit heights: its standard deviation `σ_s` and its mean
/// plane `y_s` above the mean plane of the surface heights, so that a summit at height `z`
/// touches at interference `ω = z − d`, `d = h − y_s` (App. A.1; docs/model-form.md,
/// "Summit heights").
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum SummitDistribution {
    /// The summits have the surface heights' statistics: `y_s = 0`, `σ_s = σ` (`d = h`). What
    /// the dissertation evidently used (reproduces its 7.30 μN on a Chapter 2 area).
    #[default]
    Surface,
    /// McCool: `y_s = 0.045944·σ/β`, `σ_s = σ·√(1 − 3.717e-4/β²)`; needs `β > 0.0193`.
    McCool,
    /// `σ_s = sigma_ratio·σ`, `y_s = offset_ratio·σ`: fitted to Fig. 2.11
    /// ([`summits::fit_two_point`]) or measured on the surfaces (the contact stage).
    Given { sigma_ratio: f64, offset_ratio: f64 },
}

/// Largest `|y_s|/σ` and `σ_s/σ` accepted for a given distribution: beyond, the summits would
/// lie outside any surface the dissertation or a measured map describes.
const MAX_GIVEN_SUMMIT_RATIO: f64 = 10.0;

/// Single-summit static-friction law (eq. A.6; docs/contact.md, "Friction"). An enum so that
/// Kogut & Etsion's own fit, whose constants could not be recovered, can be added.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrictionLaw {
    /// `Q_max = τ_s·A(ω)`, `τ_s = H/(2.8·√3)` (von Mises shear yield with KE's `H = 2.8·Y`),
    /// so `Q = τ_s·A_r` and `Q/A_r` is the constant `τ_s`. Anchored on the dissertation's
    /// Ch. 3.1 single-asperity numbers.
    #[default]
    JunctionShear,
    /// `Q_max/L_c = 0.4155·ω*^0.970` on elastic summits only (back-solved from Ch. 3.1).
    SeedPowerElastic,
    /// Eq. A.6 read as Kogut & Etsion's static friction (KE 2004): each summit's maximum
    /// static friction at its adhesion-augmented load, `Q_max/L_c = 0.4155·(P/L_c +
    /// F_s/L_c)^(0.970/1.5)` with `F_s = 2πΔγ_max·R·f_el(ω/ε)`, summed over the elastic and
    /// elastic-plastic summits (`0 < ω* ≤ 110`). The power law is the Ch. 3.1 back-solve
    /// ([`asperity::KE_STATIC_COEFFICIENT`] says why KE's constants are not used).
    KeStatic,
}

/// Surface (adhesion) energy model (eq. 3.50, Fig. 3.17).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceEnergy {
    /// `Δγ` constant [N/m] (Chapters 2 and 4).
    Constant { delta_gamma: f64 },
    /// `Δγ(s) = c1·exp(−c2·s) + c3` for `ε ≤ s ≤ t`, held at `Δγ(ε)` below `ε`; the
    /// non-contacting summits see `Δγ(t)`. `c1`, `c3` [N/m], `c2` [1/m] (Chapter 3.2.3).
    Variable { c1: f64, c2: f64, c3: f64 },
}

impl SurfaceEnergy {
    /// Chapter 3.2.3 variable energy: `c2 = 2.41 nm⁻¹` [seed]; `c1 = 100 mN/m`,
    /// `c3 = 19 mN/m` [assumption, eq. 3.50: the seed dropped them; replace with a Yeo et al.
    /// 2008 fit when available].
    pub const fn seed_variable() -> Self {
        SurfaceEnergy::Variable {
            c1: 0.100,
            c2: 2.41e9,
            c3: 0.019,
        }
    }
}

/// Interface and material inputs of the ISBL model (Tables 2.2, 3.2). SI units throughout.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IsblParams {
    /// `σ`: RMS of the combined surface heights [m].
    pub sigma: f64,
    /// `R`: combined mean summit radius [m].
    pub summit_radius: f64,
    /// `η`: combined summit areal density [1/m²].
    pub summit_density: f64,
    /// `E1`, `ν1`: slider (TFC) overcoat Young's modulus [Pa] and Poisson ratio.
    pub slider_modulus: f64,
    pub slider_poisson: f64,
    /// `E2`, `ν2`: disk overcoat Young's modulus [Pa] and Poisson ratio.
    pub disk_modulus: f64,
    pub disk_poisson: f64,
    /// `ν` of the yielding (softer, DLC) body, for KE's `K = 0.454 + 0.41·ν`.
    pub yielding_poisson: f64,
    /// `H`: hardness of the yielding body [Pa].
    pub hardness: f64,
    /// `ε`: Lennard-Jones equilibrium spacing [m].
    pub lj_spacing: f64,
    /// `t`: total lubricant thickness [m] (lubricant occupies `3σ ≤ h < 3σ + t`).
    pub lubricant_thickness: f64,
    pub surface_energy: SurfaceEnergy,
    pub summits: SummitDistribution,
    pub friction_law: FrictionLaw,
}

/// The DLC overcoats of every parameter set: `E1 = E2 = 280 GPa` [seed: T2.2, T2.4, T4.2],
/// `ν = 0.25` [seed, back-solved from ψ = 0.52 in Ch. 2.1; dropped in the tables].
const DLC_MODULUS: f64 = 280e9;
const DLC_POISSON: f64 = 0.25;

impl IsblParams {
    /// Initial 2-DOF interface (Ch. 2.1, Table 2.2). σ = 0.87 nm = √(0.34² + 0.80²) [seed],
    /// R = 0.43 μm [seed], η = 124 μm⁻² [assumption: T2.2 dropped; T2.4/T4.2 give it for the
    /// same surfaces], H = 13 GPa [seed], ε = 0.3 nm [assumption: the author's T3.2 value],
    /// t = 1.5 nm [seed: T2.1], Δγ = 0.06 N/m [seed, back-solved from F_s = 0.98 mN, §9 #2c].
    pub fn initial_2dof() -> Self {
        IsblParams {
            sigma: 0.87e-9,
            summit_radius: 0.43e-6,
            summit_density: 124e12,
            slider_modulus: DLC_MODULUS,
            slider_poisson: DLC_POISSON,
            disk_modulus: DLC_MODULUS,
            disk_poisson: DLC_POISSON,
            yielding_poisson: DLC_POISSON,
            hardness: 13e9,
            lj_spacing: 0.3e-9,
            lubricant_thickness: 1.5e-9,
            surface_energy: SurfaceEnergy::Constant { delta_gamma: 0.06 },
            summits: SummitDistribution::Surface,
            friction_law: FrictionLaw::JunctionShear,
        }
    }

    /// Improved 2-DOF interface (Ch. 2.2, Table 2.4): as the initial set but σ = 0.50 nm
    /// [seed, back-solved: A_n = 55 μm² at 12 nm with a 3σ cut and "3σ ≈ 1.5 nm"; T2.4
    /// prints 0.87 nm, which contradicts both]; η = 124 μm⁻² [seed: T2.4].
    pub fn improved_2dof() -> Self {
        IsblParams {
            sigma: 0.50e-9,
            ..Self::initial_2dof()
        }
    }

    /// 3-DOF interface (Ch. 4, Table 4.2): σ = 0.50 nm [seed: "3σ = 1.5 nm"], R = 0.43 μm
    /// [assumption: T4.2 dropped; Ch. 4 reuses the improved model's set], η = 124 μm⁻²
    /// [seed: T4.2], H = 13 GPa [seed], t = 1.5 nm [seed], Δγ = 0.06 N/m [assumption: T4.2
    /// value dropped]. MTL runs use `SurfaceEnergy::seed_variable()` instead.
    pub fn three_dof() -> Self {
        Self::improved_2dof()
    }

    /// Rough-surface example of the MTL chapter (Ch. 3.2, Table 3.2, interface of Yeo et al.):
    /// σ = 0.82 nm, R = 3.89 μm, H = 15 GPa, ε = 0.3 nm, t = 1.5 nm [seed: T3.2];
    /// η = 15.7 μm⁻² [assumption: dropped; β = 0.050]; E, ν as the DLC of Ch. 2/4
    /// [assumption: dropped]; variable surface energy [seed: T3.2 c2; c1, c3 assumption].
    pub fn mtl_table_3_2() -> Self {
        IsblParams {
            sigma: 0.82e-9,
            summit_radius: 3.89e-6,
            summit_density: 15.7e12,
            hardness: 15e9,
            surface_energy: SurfaceEnergy::seed_variable(),
            ..Self::initial_2dof()
        }
    }

    /// Checks every input against its physical range.
    pub fn validate(&self) -> Result<(), ContactError> {
        fn positive(name: &'static str, v: f64) -> Result<(), ContactError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ContactError::parameter(name, v, "must be finite and > 0"))
            }
        }
        fn poisson(name: &'static str, v: f64) -> Result<(), ContactError> {
            if v.is_finite() && v > -1.0 && v < 0.5 {
                Ok(())
            } else {
                Err(ContactError::parameter(
                    name,
                    v,
                    "Poisson ratio must lie in (-1, 0.5)",
                ))
            }
        }
        positive("sigma", self.sigma)?;
        positive("summit_radius", self.summit_radius)?;
        positive("summit_density", self.summit_density)?;
        positive("slider_modulus", self.slider_modulus)?;
        positive("disk_modulus", self.disk_modulus)?;
        poisson("slider_poisson", self.slider_poisson)?;
        poisson("disk_poisson", self.disk_poisson)?;
        poisson("yielding_poisson", self.yielding_poisson)?;
        // K = 0.454 + 0.41ν must stay positive (ν > −1.107 always holds for ν > −1).
        positive("hardness", self.hardness)?;
        positive("lj_spacing", self.lj_spacing)?;
        if !(self.lubricant_thickness.is_finite() && self.lubricant_thickness >= 0.0) {
            return Err(ContactError::parameter(
                "lubricant_thickness",
                self.lubricant_thickness,
                "must be finite and >= 0",
            ));
        }
        match self.surface_energy {
            SurfaceEnergy::Constant { delta_gamma } => {
                if !(delta_gamma.is_finite() && delta_gamma >= 0.0) {
                    return Err(ContactError::parameter(
                        "delta_gamma",
                        delta_gamma,
                        "must be finite and >= 0",
                    ));
                }
            }
            SurfaceEnergy::Variable { c1, c2, c3 } => {
                for (name, v) in [("c1", c1), ("c2", c2), ("c3", c3)] {
                    if !(v.is_finite() && v >= 0.0) {
                        return Err(ContactError::parameter(name, v, "must be finite and >= 0"));
                    }
                }
            }
        }
        match self.summits {
            SummitDistribution::Surface => {}
            SummitDistribution::McCool => {
                let beta = self.sigma * self.summit_radius * self.summit_density;
                if beta.is_nan() || beta <= MCCOOL_MIN_BETA {
                    return Err(ContactError::parameter(
                        "beta = sigma*R*eta",
                        beta,
                        "McCool's summit relations need beta > 0.0193",
                    ));
                }
            }
            SummitDistribution::Given {
                sigma_ratio,
                offset_ratio,
            } => {
                if !(sigma_ratio.is_finite()
                    && sigma_ratio > 0.0
                    && sigma_ratio <= MAX_GIVEN_SUMMIT_RATIO)
                {
                    return Err(ContactError::parameter(
                        "sigma_s/sigma",
                        sigma_ratio,
                        format!("must lie in (0, {MAX_GIVEN_SUMMIT_RATIO}]"),
                    ));
                }
                if !(offset_ratio.is_finite() && offset_ratio.abs() <= MAX_GIVEN_SUMMIT_RATIO) {
                    return Err(ContactError::parameter(
                        "y_s/sigma",
                        offset_ratio,
                        format!(
                            "must lie in [-{MAX_GIVEN_SUMMIT_RATIO}, {MAX_GIVEN_SUMMIT_RATIO}]"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// `E* = [(1−ν1²)/E1 + (1−ν2²)/E2]⁻¹` (seed eq. A.5).
    pub fn composite_modulus(&self) -> f64 {
        super::reduced_modulus(
            self.slider_modulus,
            self.slider_poisson,
            self.disk_modulus,
            self.disk_poisson,
        )
    }
}

/// Lower validity limit of McCool's `σ_s` relation (`1 − 3.717e-4/β² > 0`).
const MCCOOL_MIN_BETA: f64 = 0.0193;
/// Integration cut-off of the Gaussian, in `σ_s` beyond its centre: `φ(14σ_s)/φ(0) = e^-98`.
const GAUSSIAN_CUTOFF_SIGMAS: f64 = 14.0;
/// Relative tolerance of every quadrature (docs/contact.md: 1e-10 is cheap; acceptance is 1e-6).
const QUADRATURE_REL_TOL: f64 = 1e-10;
const QUADRATURE_MAX_SEGMENTS: usize = 2000;
/// Largest `|h|/σ` accepted: beyond it `d + ω` loses the digits the Gaussian needs
/// (rounding of `|d|·ε_mach` against `σ`), and the interface is meaningless anyway (the
/// contact curves are exactly 0 from `h* ≈ 40`; the adhesion tail is the §6.4 formula).
const MAX_SEPARATION_SIGMAS: f64 = 1e4;
/// Below `h* = −4` is deep interference, flagged (docs/contact.md).
const DEEP_INTERFERENCE_H_STAR: f64 = -4.0;

/// Quantities derived once from [`IsblParams`] (App. A.1; docs/contact.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IsblDerived {
    /// `E*` [Pa].
    pub composite_modulus: f64,
    /// KE `K = 0.454 + 0.41·ν`.
    pub k_factor: f64,
    /// `ω_c = (πKH/(2E*))²·R` [m].
    pub critical_interference: f64,
    /// `L_c = (2/3)πKHRω_c` [N].
    pub critical_load: f64,
    /// `A_c = πRω_c` [m²].
    pub critical_area: f64,
    /// `β = σRη`.
    pub beta: f64,
    /// Dissertation plasticity index `ψ = (E*/H)·√(σ/R)`.
    pub plasticity_index: f64,
    /// KE plasticity index `ψ_KE = √(σ/ω_c)`.
    pub plasticity_index_ke: f64,
    /// `y_s`: summit mean plane above the surface mean plane [m] (0 for `Surface`).
    pub summit_offset: f64,
    /// `σ_s`: standard deviation of summit heights [m].
    pub summit_sigma: f64,
    /// Junction shear strength `τ_s = H/(2.8·√3)` [Pa].
    pub junction_shear_strength: f64,
    /// `Δγ_min` (non-contacting summits) and `Δγ_max` (solid-contacting) [N/m].
    pub delta_gamma_min: f64,
    pub delta_gamma_max: f64,
    /// True when `ψ_KE > 1`: summits beyond `ω_c` may then carry a noticeable share of the
    /// solid adhesion, for which the elastic `f_el` is used without KE's fits (docs/contact.md).
    pub elastic_plastic_adhesion_assumed: bool,
    /// `2πΔγ_max·R/L_c`: a contacting summit's adhesion force over `L_c` per unit `f_el` (the
    /// load `ke_static` adds to the contact load).
    pub adhesion_load_ratio: f64,
}

/// All ISBL curves at one solid separation `h`, per unit nominal area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IsblPoint {
    /// Solid separation `h` [m].
    pub separation: f64,
    /// `P(h)`: contact force per unit nominal area [Pa].
    pub contact_pressure: f64,
    /// `k_c = −dP/dh` [Pa/m].
    pub contact_stiffness: f64,
    /// `A_r/A_n`.
    pub real_area_fraction: f64,
    /// `−d(A_r/A_n)/dh` [1/m].
    pub real_area_gradient: f64,
    /// `Q(h)`: maximum static friction per unit nominal area [Pa].
    pub friction_stress: f64,
    /// `k_fr = −dQ/dh` [Pa/m].
    pub friction_stiffness: f64,
    /// `F_nc`, `F_lc`, `F_sc`: adhesion of non-contacting, lubricant-contacting and
    /// solid-contacting summits [Pa] (magnitudes, pulling the surfaces together).
    pub adhesion_non_contacting: f64,
    pub adhesion_lubricant: f64,
    pub adhesion_solid: f64,
    /// `F_s = F_nc + F_lc + F_sc` [Pa].
    pub adhesion: f64,
    /// `dF_s/dh` [Pa/m] (negative: adhesion falls with separation).
    pub adhesion_gradient: f64,
    /// `n_c`: contacting summits per unit nominal area [1/m²].
    pub contacts_per_area: f64,
    /// `h* < −4`: deeper interference than the dissertation simulates (docs/contact.md).
    pub deep_interference: bool,
}

/// One summit's contact (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AsperityContact {
    /// Normal load [N].
    pub load: f64,
    /// Contact area [m²].
    pub area: f64,
    /// Maximum static friction `Q_max` [N].
    pub friction: f64,
}

/// One immutable ISBL interface (docs/contact.md): validated inputs plus derived constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IsblModel {
    params: IsblParams,
    derived: IsblDerived,
}

impl IsblModel {
    /// Validates `params` and derives the constants of App. A.1.
    pub fn new(params: IsblParams) -> Result<Self, ContactError> {
        params.validate()?;
        let composite_modulus = params.composite_modulus();
        let k_factor = 0.454 + 0.41 * params.yielding_poisson;
        let critical_interference = (PI * k_factor * params.hardness / (2.0 * composite_modulus))
            .powi(2)
            * params.summit_radius;
        let critical_load = 2.0 / 3.0
            * PI
            * k_factor
            * params.hardness
            * params.summit_radius
            * critical_interference;
        let critical_area = PI * params.summit_radius * critical_interference;
        let beta = params.sigma * params.summit_radius * params.summit_density;
        let plasticity_index =
            composite_modulus / params.hardness * (params.sigma / params.summit_radius).sqrt();
        let plasticity_index_ke = (params.sigma / critical_interference).sqrt();
        let (summit_offset, summit_sigma) = match params.summits {
            SummitDistribution::Surface => (0.0, params.sigma),
            SummitDistribution::McCool => (
                0.045944 * params.sigma / beta,
                params.sigma * (1.0 - 3.717e-4 / (beta * beta)).sqrt(),
            ),
            SummitDistribution::Given {
                sigma_ratio,
                offset_ratio,
            } => (offset_ratio * params.sigma, sigma_ratio * params.sigma),
        };
        let junction_shear_strength = params.hardness / (2.8 * 3f64.sqrt());
        let (delta_gamma_min, delta_gamma_max) = match params.surface_energy {
            SurfaceEnergy::Constant { delta_gamma } => (delta_gamma, delta_gamma),
            SurfaceEnergy::Variable { .. } => (
                surface_energy_at(&params, params.lubricant_thickness),
                surface_energy_at(&params, params.lj_spacing),
            ),
        };
        let adhesion_load_ratio = 2.0 * PI * delta_gamma_max * params.summit_radius / critical_load;
        let derived = IsblDerived {
            composite_modulus,
            k_factor,
            critical_interference,
            critical_load,
            critical_area,
            beta,
            plasticity_index,
            plasticity_index_ke,
            summit_offset,
            summit_sigma,
            junction_shear_strength,
            delta_gamma_min,
            delta_gamma_max,
            elastic_plastic_adhesion_assumed: plasticity_index_ke > 1.0,
            adhesion_load_ratio,
        };
        let all_finite = [
            composite_modulus,
            critical_interference,
            critical_load,
            summit_sigma,
        ]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0);
        // y_s may be negative for a given distribution (summits below the surface mean plane).
        if !all_finite
            || !summit_offset.is_finite()
            || critical_interference <= 0.0
            || summit_sigma <= 0.0
        {
            return Err(ContactError::parameter(
                "derived constants",
                format!("{derived:?}"),
                "inputs give a non-finite or non-positive omega_c, E* or sigma_s",
            ));
        }
        Ok(IsblModel { params, derived })
    }

    pub fn params(&self) -> &IsblParams {
        &self.params
    }

    pub fn derived(&self) -> &IsblDerived {
        &self.derived
    }

    /// Every curve at solid separation `h` [m]. Errors for non-finite `h`, `|h| > 1e4·σ`,
    /// or if a quadrature misses its tolerance.
    pub fn at(&self, h: f64) -> Result<IsblPoint, ContactError> {
        if !(h.is_finite() && h.abs() <= MAX_SEPARATION_SIGMAS * self.params.sigma) {
            return Err(ContactError::parameter(
                "h",
                h,
                format!("separation must be finite and within ±{MAX_SEPARATION_SIGMAS:e} σ"),
            ));
        }
        let p = &self.params;
        let dv = &self.derived;
        let d = h - dv.summit_offset;
        let contact = self.contact_integrals(d)?;
        let eta = p.summit_density;
        let contact_pressure = eta * dv.critical_load * contact[0];
        let contact_stiffness = eta * dv.critical_load * contact[1];
        let real_area_fraction = eta * dv.critical_area * contact[2];
        let real_area_gradient = eta * dv.critical_area * contact[3];
        let contacts_per_area = eta * contact[4];
        let (friction_stress, friction_stiffness) = match p.friction_law {
            FrictionLaw::JunctionShear => (
                dv.junction_shear_strength * real_area_fraction,
                dv.junction_shear_strength * real_area_gradient,
            ),
            FrictionLaw::SeedPowerElastic | FrictionLaw::KeStatic => (
                eta * dv.critical_load * contact[5],
                eta * dv.critical_load * contact[6],
            ),
        };
        let adhesion_scale = 2.0 * PI * p.summit_radius * eta;
        let adhesion_solid = adhesion_scale * dv.delta_gamma_max * contact[7];
        let d_solid = adhesion_scale * dv.delta_gamma_max * contact[8];
        let lubricant = self.lubricant_integrals(d)?;
        let non_contact = self.non_contact_integrals(d)?;
        let adhesion_lubricant = adhesion_scale * lubricant[0];
        let adhesion_non_contacting = adhesion_scale * dv.delta_gamma_min * non_contact[0];
        let adhesion_gradient =
            adhesion_scale * (lubricant[1] + dv.delta_gamma_min * non_contact[1]) + d_solid;
        Ok(IsblPoint {
            separation: h,
            contact_pressure,
            contact_stiffness,
            real_area_fraction,
            real_area_gradient,
            friction_stress,
            friction_stiffness,
            adhesion_non_contacting,
            adhesion_lubricant,
            adhesion_solid,
            adhesion: adhesion_non_contacting + adhesion_lubricant + adhesion_solid,
            adhesion_gradient,
            contacts_per_area,
            deep_interference: h / p.sigma < DEEP_INTERFERENCE_H_STAR,
        })
    }

    /// `P(h)` alone [Pa]: the contact integrals of [`IsblModel::at`] without the adhesion
    /// ones (for the summit-distribution fits, which evaluate it thousands of times).
    pub fn contact_pressure(&self, h: f64) -> Result<f64, ContactError> {
        if !(h.is_finite() && h.abs() <= MAX_SEPARATION_SIGMAS * self.params.sigma) {
            return Err(ContactError::parameter(
                "h",
                h,
                format!("separation must be finite and within ±{MAX_SEPARATION_SIGMAS:e} σ"),
            ));
        }
        let contact = self.contact_integrals(h - self.derived.summit_offset)?;
        Ok(self.params.summit_density * self.derived.critical_load * contact[0])
    }

    /// One summit at interference `ω` [m] (KE laws, SI units): load [N], contact area [m²]
    /// and maximum static friction [N] under the configured friction law. Zero for `ω ≤ 0`.
    pub fn asperity_at(&self, omega: f64) -> Result<AsperityContact, ContactError> {
        if !omega.is_finite() {
            return Err(ContactError::parameter(
                "omega",
                omega,
                "interference must be finite",
            ));
        }
        let dv = &self.derived;
        let omega_star = omega / dv.critical_interference;
        let load = dv.critical_load * asperity::ke_load_ratio(omega_star, dv.k_factor);
        let area = dv.critical_area * asperity::ke_area_ratio(omega_star);
        let friction = match self.params.friction_law {
            FrictionLaw::JunctionShear => dv.junction_shear_strength * area,
            FrictionLaw::SeedPowerElastic => {
                dv.critical_load * seed_power_friction_ratio(omega_star)
            }
            FrictionLaw::KeStatic => {
                let adhesion = if omega > 0.0 {
                    adhesion_factor_elastic_fast(omega / self.params.lj_spacing)?
                } else {
                    0.0
                };
                dv.critical_load
                    * ke_static_friction_ratio_in(
                        KeRegime::of(omega_star),
                        omega_star,
                        dv.k_factor,
                        dv.adhesion_load_ratio * adhesion,
                    )
            }
        };
        Ok(AsperityContact {
            load,
            area,
            friction,
        })
    }

    /// Gaussian summit density `φ(z)`.
    fn density(&self, z: f64) -> f64 {
        let s = self.derived.summit_sigma;
        (-0.5 * (z / s) * (z / s)).exp() / (s * (2.0 * PI).sqrt())
    }

    /// Integrals over the solid-contacting summits, in `ω = z − d ∈ [0, ω_max]`
    /// (dimensionless; scaled by the caller):
    /// `[∫p*φ, ∫p*·(z/σ_s²)φ, ∫a*φ, ∫a*·(z/σ_s²)φ, ∫φ, ∫q*φ, ∫q*·(z/σ_s²)φ, ∫f_el φ,
    ///   −∫f_el·(z/σ_s²)φ]` where `z/σ_s²·φ = −φ'` turns `−d/dh` into a density weight, and
    /// `q*` is `Q_max/L_c` of the `ke_static` law, or the seed power law for the other two
    /// (which the junction-shear law does not read, but whose tolerance it has always shared).
    ///
    /// The elastic piece uses `ω = ω_c·u²` so the `ω^{1/2}`-type endpoint behaviour of the
    /// Hertz laws becomes polynomial; the other pieces are the KE regimes in `ω`.
    fn contact_integrals(&self, d: f64) -> Result<[f64; 9], ContactError> {
        let dv = &self.derived;
        let wc = dv.critical_interference;
        let sigma_s = dv.summit_sigma;
        let eps = self.params.lj_spacing;
        let k = dv.k_factor;
        let ke_static = self.params.friction_law == FrictionLaw::KeStatic;
        let adhesion_load_ratio = dv.adhesion_load_ratio;
        let omega_max = (-d).max(0.0) + GAUSSIAN_CUTOFF_SIGMAS * sigma_s;
        let regimes = [
            (KeRegime::ElasticPlasticI, 1.0, 6.0),
            (KeRegime::ElasticPlasticII, 6.0, 110.0),
            (KeRegime::FullyPlastic, 110.0, f64::INFINITY),
        ];
        let mut pieces = vec![(0, 0.0, (omega_max / wc).min(1.0).sqrt())];
        for (index, &(_, lo, hi)) in regimes.iter().enumerate() {
            let a = lo * wc;
            let b = (hi * wc).min(omega_max);
            if b > a {
                pieces.push((index + 1, a, b));
            }
        }
        let mut failure = None;
        let result = quadrature::integrate(
            |piece, x| {
                let (omega, jacobian, regime) = if piece == 0 {
                    (wc * x * x, 2.0 * wc * x, KeRegime::Elastic)
                } else {
                    (x, 1.0, regimes[piece - 1].0)
                };
                let omega_star = omega / wc;
                let z = d + omega;
                let weight = self.density(z) * jacobian;
                let slope = z / (sigma_s * sigma_s);
                let load = ke_load_ratio_in(regime, omega_star, k);
                let area = ke_area_ratio_in(regime, omega_star);
                let adhesion = match adhesion_factor_elastic_fast(omega / eps) {
                    Ok(v) => v,
                    Err(e) => {
                        failure = Some(e);
                        f64::NAN
                    }
                };
                let friction = if ke_static {
                    ke_static_friction_ratio_in(
                        regime,
                        omega_star,
                        k,
                        adhesion_load_ratio * adhesion,
                    )
                } else {
                    seed_power_friction_ratio(omega_star)
                };
                [
                    load * weight,
                    load * slope * weight,
                    area * weight,
                    area * slope * weight,
                    weight,
                    friction * weight,
                    friction * slope * weight,
                    adhesion * weight,
                    -adhesion * slope * weight,
                ]
            },
            &pieces,
            QUADRATURE_REL_TOL,
            QUADRATURE_MAX_SEGMENTS,
        );
        match failure {
            Some(e) => Err(e),
            None => result,
        }
    }

    /// Lubricant-contacting summits, in the local lubricant gap `s = d − z ∈ [0, t]`:
    /// `[∫Δγ(s)φ(d−s) ds, ∫Δγ(s)φ'(d−s) ds]` (the second is `d/dh` of the first).
    /// Split at `s = ε` where the variable `Δγ(s)` has its kink.
    fn lubricant_integrals(&self, d: f64) -> Result<[f64; 2], ContactError> {
        let t = self.params.lubricant_thickness;
        let eps = self.params.lj_spacing;
        let sigma_s = self.derived.summit_sigma;
        let pieces = if eps < t {
            vec![(0, 0.0, eps), (0, eps, t)]
        } else {
            vec![(0, 0.0, t)]
        };
        quadrature::integrate(
            |_, s| {
                let z = d - s;
                let value = surface_energy_at(&self.params, s) * self.density(z);
                [value, -z / (sigma_s * sigma_s) * value]
            },
            &pieces,
            QUADRATURE_REL_TOL,
            QUADRATURE_MAX_SEGMENTS,
        )
    }

    /// Non-contacting summits, in `x = d − t − z ≥ 0` (distance below the mobile-lubricant
    /// surface; gap `g = x + ε`, App. A.1 convention):
    /// `[∫L(x)φ(d−t−x) dx, ∫L(x)φ'(d−t−x) dx]`, `L = (4/3)[(ε/g)² − ¼(ε/g)⁸]`.
    ///
    /// Near the lubricant surface (`x` up to `max(10ε, d − t − 14σ_s)`, split at `ε`, `10ε`)
    /// the variable is `x` (piece 0), where the LJ law varies fastest. Over the Gaussian
    /// (piece 1) the variable is `z` itself, so `z` carries no rounding from `d − t − x` when
    /// the surfaces are far apart; split at the Gaussian centre `z = 0`.
    fn non_contact_integrals(&self, d: f64) -> Result<[f64; 2], ContactError> {
        let t = self.params.lubricant_thickness;
        let eps = self.params.lj_spacing;
        let sigma_s = self.derived.summit_sigma;
        let cutoff = GAUSSIAN_CUTOFF_SIGMAS * sigma_s;
        let top = d - t;
        let x_max = top.max(0.0) + cutoff;
        let x_switch = (10.0 * eps).max(top - cutoff).min(x_max);
        let mut pieces: Vec<(usize, f64, f64)> = Vec::new();
        let mut x_breaks = vec![0.0, eps, 10.0 * eps, x_switch];
        x_breaks.retain(|b| *b <= x_switch);
        x_breaks.sort_by(f64::total_cmp);
        x_breaks.dedup();
        pieces.extend(x_breaks.windows(2).map(|w| (0, w[0], w[1])));
        let (z_low, z_high) = (top - x_max, top - x_switch);
        if z_low < 0.0 && 0.0 < z_high {
            pieces.push((1, z_low, 0.0));
            pieces.push((1, 0.0, z_high));
        } else {
            pieces.push((1, z_low, z_high));
        }
        quadrature::integrate(
            |piece, v| {
                let (x, z) = if piece == 0 {
                    (v, top - v)
                } else {
                    (top - v, v)
                };
                let r = eps / (x + eps);
                let r2 = r * r;
                let r8 = r2 * r2 * r2 * r2;
                let value = 4.0 / 3.0 * (r2 - 0.25 * r8) * self.density(z);
                [value, -z / (sigma_s * sigma_s) * value]
            },
            &pieces,
            QUADRATURE_REL_TOL,
            QUADRATURE_MAX_SEGMENTS,
        )
    }
}

/// Surface energy at local lubricant gap `s` [N/m] (eq. 3.50): constant, or
/// `c1·exp(−c2·max(s, ε)) + c3` (held at `Δγ(ε)` below the LJ spacing).
pub fn surface_energy_at(params: &IsblParams, s: f64) -> f64 {
    match params.surface_energy {
        SurfaceEnergy::Constant { delta_gamma } => delta_gamma,
        SurfaceEnergy::Variable { c1, c2, c3 } => c1 * (-c2 * s.max(params.lj_spacing)).exp() + c3,
    }
}

/// Convenience: validate `params`, build the model and evaluate it at `h` (for repeated
/// evaluation build an [`IsblModel`] once instead).
pub fn isbl_at(params: &IsblParams, h: f64) -> Result<IsblPoint, ContactError> {
    IsblModel::new(*params)?.at(h)
}
