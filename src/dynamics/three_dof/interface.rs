//! Interfacial forces of one 3-DOF feature (§4.1, eqs. 3.55–3.60, App. A;
//! docs/contact.md): from the feature's solid spacing `s`, its rate and its nominal
//! area `A_n`, the upward normal force `N = F_c + P_lub − F_s`, the friction `Q` (solid +
//! lubricant, along −X), the adhesion and the real area. Pure; SI.
//!
//! * **Solid** (`s < 3σ`): the 2-DOF reading of eq. 2.16 per feature,
//!   `F_c = A_n k_c(s)(3σ − s) − c_c ṡ` (or the static curve `A_n P(s) − c_c ṡ`), clipped at 0,
//!   with `c_c = 2ζ_c √(A_n k_c(2.5σ) m)` (§3.4 with the feature's own area); friction and real
//!   area from the quasi-static equivalence `A_n P(h*) = F_c`.
//! * **Adhesion**: ISBL `A_n F_s(s)` (the MTL runs use the variable surface energy of the contact
//!   set, `SurfaceEnergy::seed_variable`).
//! * **Lubricant** (`Mtl` model, `s < 3σ + t`): the rough-surface MTL law of contact-mtl §4.5 with
//!   the ISBL solid scaled by the feature's `A_n` (the lubricant law itself is a whole-interface
//!   law: not scaled by `A_n`, §4.5 decision 1). `Isbl` model: no lubricant force.

use super::super::contact_force::ContactForceForm;
use super::super::DynamicsError;
use crate::contact::lookup::IsblLookup;
use crate::contact::mtl::{RoughMtl, SolidContact, SolidResponse};

/// Which interfacial law acts on the features (switch `contact_model`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InterfaceLaw {
    /// ISBL solid contact and adhesion only (Chapter 2's interface).
    Isbl,
    /// ISBL solid + the MTL lubricant forces (Chapter 3's law; Chapter 4's "MTL" runs).
    Mtl(RoughMtl),
}

/// Forces on one feature at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FeatureForces {
    /// Solid contact force `F_c ≥ 0` [N].
    pub contact_force: f64,
    /// Lubricant bearing force `P_lub ≥ 0` [N].
    pub lubricant_force: f64,
    /// Adhesion `F_s ≥ 0` [N] (pulls toward the disk).
    pub adhesion: f64,
    /// Friction `Q ≥ 0` [N], solid + lubricant (acts along −X).
    pub friction: f64,
    /// Real contact area of the solid contact [m²].
    pub real_area: f64,
    /// The contact damper's part of `contact_force`, `−c_c ṡ` [N] (0 when clipped): the
    /// elastic part is `contact_force − contact_damping`.
    pub contact_damping: f64,
    /// The contact damper would have pulled (`F_c` clipped to 0).
    pub clipped: bool,
}

impl FeatureForces {
    /// Upward normal force on the slider `N = F_c + P_lub − F_s` [N].
    #[inline]
    pub fn normal(&self) -> f64 {
        self.contact_force + self.lubricant_force - self.adhesion
    }
}

/// The ISBL table times an area, borrowed (the MTL law's solid for one feature, or for the
/// 2-DOF bulge with `lubricant = mtl`).
pub(crate) struct AreaIsbl<'a> {
    pub(crate) lookup: &'a IsblLookup,
    pub(crate) area: f64,
}

impl SolidContact for AreaIsbl<'_> {
    fn response(&self, separation: f64) -> SolidResponse {
        self.lookup
            .at(separation)
            .map(|f| SolidResponse {
                normal: f.pressure * self.area,
                friction: f.friction * self.area,
                normal_stiffness: f.stiffness * self.area,
                friction_stiffness: f.friction_stiffness * self.area,
            })
            .unwrap_or_default()
    }
}

/// The interface every feature of one case sees.
pub struct FeatureInterface<'a> {
    isbl: &'a IsblLookup,
    law: InterfaceLaw,
    form: ContactForceForm,
    sigma: f64,
    /// `k_c(2.5σ)` per unit area [Pa/m] and the slider mass [kg], for `c_c` per feature.
    reference_stiffness: f64,
    mass: f64,
    contact_damping_ratio: f64,
    /// Upper bound of the solid contact's mean pressure over the nominal area `F_c/A_n` [Pa]
    /// (none by default; an experiment of docs/model-form.md, not a `pipeline.toml` key).
    pressure_cap: Option<f64>,
}

fn numerical(e: crate::contact::ContactError) -> DynamicsError {
    DynamicsError::Numerical(e.to_string())
}

impl<'a> FeatureInterface<'a> {
    pub fn new(
        isbl: &'a IsblLookup,
        law: InterfaceLaw,
        form: ContactForceForm,
        contact_damping_ratio: f64,
        mass: f64,
    ) -> Result<Self, DynamicsError> {
        let sigma = isbl.model().params().sigma;
        if let InterfaceLaw::Mtl(m) = &law {
            let film_sigma = m.film().sigma;
            if (film_sigma / sigma - 1.0).abs() > 1e-9 {
                return Err(DynamicsError::parameter(
                    "MTL film σ (m)",
                    film_sigma,
                    format!("must equal the ISBL interface's σ = {sigma:e} m"),
                ));
            }
        }
        super::super::require_in(
            "contact damping ratio ζ_c",
            contact_damping_ratio,
            0.0,
            10.0,
            "",
        )?;
        let reference_stiffness = isbl.at(2.5 * sigma).map_err(numerical)?.stiffness;
        Ok(FeatureInterface {
            isbl,
            law,
            form,
            sigma,
            reference_stiffness,
            mass,
            contact_damping_ratio,
            pressure_cap: None,
        })
    }

    /// Cap the solid contact force at `cap · A_n` (e.g. the hardness: the real area cannot
    /// exceed the nominal one, which the sparse-asperity ISBL sum does at deep penetration,
    /// A_r/A_n > 1 below h* ≈ −11). Experiments only (docs/model-form.md).
    pub fn with_pressure_cap(mut self, cap: f64) -> Result<Self, DynamicsError> {
        super::super::require_positive("contact pressure cap (Pa)", cap)?;
        self.pressure_cap = Some(cap);
        Ok(self)
    }

    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    pub fn law(&self) -> &InterfaceLaw {
        &self.law
    }

    /// Spacing below which a feature is in solid contact (`3σ`).
    pub fn solid_threshold(&self) -> f64 {
        3.0 * self.sigma
    }

    /// Spacing below which a feature touches the lubricant (`3σ + t`).
    pub fn lubricant_surface(&self) -> f64 {
        3.0 * self.sigma + self.isbl.model().params().lubricant_thickness
    }

    /// Contact damping coefficient of a feature of nominal area `area` [N·s/m].
    pub fn contact_damping(&self, area: f64) -> f64 {
        2.0 * self.contact_damping_ratio * (area * self.reference_stiffness * self.mass).sqrt()
    }

    /// Forces on a feature at solid spacing `spacing` moving at `spacing_rate`, nominal area
    /// `area` (0 beyond the adhesion range: no force at all).
    pub fn forces(
        &self,
        spacing: f64,
        spacing_rate: f64,
        area: f64,
    ) -> Result<FeatureForces, DynamicsError> {
        let mut f = FeatureForces::default();
        if area <= 0.0 {
            return Ok(f);
        }
        let at = self.isbl.at(spacing).map_err(numerical)?;
        f.adhesion = area * at.adhesion;
        let threshold = self.solid_threshold();
        if spacing < threshold {
            let elastic = match self.form {
                ContactForceForm::InterferenceTangent => {
                    area * at.stiffness * (threshold - spacing)
                }
                ContactForceForm::StaticCurve => area * at.pressure,
                ContactForceForm::IntegratedStiffness => {
                    area * (at.pressure - self.isbl.at(threshold).map_err(numerical)?.pressure)
                }
            };
            let damper = -(self.contact_damping(area) * spacing_rate);
            let mut force = elastic + damper;
            if let Some(cap) = self.pressure_cap {
                force = force.min(cap * area);
            }
            if force > 0.0 {
                f.contact_force = force;
                f.contact_damping = damper;
                if let Some(h_star) = self.isbl.separation_for_pressure(force / area) {
                    let q = self.isbl.at(h_star).map_err(numerical)?;
                    f.friction = area * q.friction;
                    f.real_area = area * q.real_area_fraction;
                }
            } else {
                f.clipped = true;
            }
        }
        if let InterfaceLaw::Mtl(mtl) = &self.law {
            if spacing < mtl.lubricant_surface() {
                let solid = AreaIsbl {
                    lookup: self.isbl,
                    area,
                };
                let lub = mtl.with_solid(solid).lubricant(spacing);
                f.lubricant_force = lub.normal.max(0.0);
                f.friction += lub.friction.max(0.0);
            }
        }
        Ok(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::isbl::{IsblModel, IsblParams, SurfaceEnergy};
    use crate::contact::mtl::{FwmExperiment, LubricantCase, RoughFilm};

    fn lookup(variable: bool) -> IsblLookup {
        let mut p = IsblParams::three_dof();
        if variable {
            p.surface_energy = SurfaceEnergy::seed_variable();
        }
        IsblLookup::build_standard(IsblModel::new(p).unwrap()).unwrap()
    }

    fn mtl(case: LubricantCase) -> RoughMtl {
        let film = RoughFilm::new(0.5e-9, case.kappa(), 1.5e-9, 19.5).unwrap();
        let exp = FwmExperiment::fukuzawa_z03()
            .with_limiting_viscosity(case.limiting_viscosity())
            .unwrap();
        RoughMtl::from_experiment(film, &exp).unwrap()
    }

    #[test]
    fn isbl_feature_matches_the_two_dof_contact_law() {
        let isbl = lookup(false);
        let m = 1.098e-6;
        let fi = FeatureInterface::new(
            &isbl,
            InterfaceLaw::Isbl,
            ContactForceForm::InterferenceTangent,
            0.05,
            m,
        )
        .unwrap();
        let (a, s) = (55e-12, 1.2e-9);
        let at = isbl.at(s).unwrap();
        let f = fi.forces(s, 0.0, a).unwrap();
        let expected = a * at.stiffness * (1.5e-9 - s);
        assert!((f.contact_force / expected - 1.0).abs() < 1e-12);
        assert!((f.adhesion / (a * at.adhesion) - 1.0).abs() < 1e-12);
        assert_eq!(f.lubricant_force, 0.0);
        assert!(f.friction > 0.0 && f.real_area > 0.0 && f.real_area < a);
        // Quasi-static equivalence: A_n P(h*) = F_c.
        let h_star = isbl.separation_for_pressure(f.contact_force / a).unwrap();
        assert!((a * isbl.at(h_star).unwrap().pressure / f.contact_force - 1.0).abs() < 1e-8);
        // Damping: moving away fast clips the force to zero (never pulls).
        let g = fi.forces(s, 10.0, a).unwrap();
        assert!(g.clipped && g.contact_force == 0.0 && g.friction == 0.0);
        // No area, no force; flying, adhesion only.
        assert_eq!(fi.forces(s, 0.0, 0.0).unwrap(), FeatureForces::default());
        let fly = fi.forces(2.5e-9, 0.0, a).unwrap();
        assert!(fly.contact_force == 0.0 && fly.adhesion > 0.0);
        assert!((fly.normal() + fly.adhesion).abs() < 1e-30);
        // c_c = 2ζ_c √(A_n k_c(2.5σ) m).
        let kref = isbl.at(1.25e-9).unwrap().stiffness;
        assert!((fi.contact_damping(a) / (0.1 * (a * kref * m).sqrt()) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn mtl_feature_adds_the_lubricant_law_on_the_area_scaled_solid() {
        let isbl = lookup(true);
        let law = mtl(LubricantCase::Reference);
        let fi = FeatureInterface::new(
            &isbl,
            InterfaceLaw::Mtl(law),
            ContactForceForm::InterferenceTangent,
            0.05,
            1.098e-6,
        )
        .unwrap();
        let a = 150e-12;
        // Independent: the contact module's own composition through IsblLookup::as_solid.
        let arc = std::sync::Arc::new(lookup(true));
        let reference = law.with_solid(arc.as_solid(a));
        for s in [3.2e-9, 2.9e-9, 2.4e-9, 1.9e-9, 1.6e-9, 1.4e-9, 1.0e-9] {
            let f = fi.forces(s, 0.0, a).unwrap();
            let r = reference.evaluate(s);
            if s >= 3.0e-9 {
                assert_eq!(f.lubricant_force, 0.0, "above the lubricant at {s}");
            } else {
                assert!(
                    (f.lubricant_force / r.lubricant.normal - 1.0).abs() < 1e-12,
                    "P_lub at {s}: {} vs {}",
                    f.lubricant_force,
                    r.lubricant.normal
                );
            }
        }
        // Stiffer lubricant (more bonding) bears more at the end of the transition.
        let stiff = mtl(LubricantCase::MoreBonding);
        let fs = FeatureInterface::new(
            &isbl,
            InterfaceLaw::Mtl(stiff),
            ContactForceForm::InterferenceTangent,
            0.05,
            1.098e-6,
        )
        .unwrap();
        let s = 1.5e-9 + 0.6e-9;
        assert!(
            fs.forces(s, 0.0, a).unwrap().lubricant_force
                > fi.forces(s, 0.0, a).unwrap().lubricant_force
        );
    }

    #[test]
    fn film_sigma_must_match_the_interface() {
        let isbl = lookup(false);
        let film = RoughFilm::table_3_2(); // σ = 0.82 nm
        let law = RoughMtl::from_experiment(film, &FwmExperiment::fukuzawa_z03()).unwrap();
        assert!(FeatureInterface::new(
            &isbl,
            InterfaceLaw::Mtl(law),
            ContactForceForm::InterferenceTangent,
            0.05,
            1e-6
        )
        .is_err());
    }

    #[test]
    fn integrated_stiffness_feature_force_is_the_quadrature_of_k_c() {
        // F_c = A_n ∫_s^{3σ} k_c(h) dh (docs/model-form.md), by Simpson's rule on the table's
        // stiffness column (its own GW integral), against the switch's A_n [P(s) − P(3σ)].
        let isbl = lookup(false);
        let fi = FeatureInterface::new(
            &isbl,
            InterfaceLaw::Isbl,
            ContactForceForm::IntegratedStiffness,
            0.05,
            1.098e-6,
        )
        .unwrap();
        let (a, threshold) = (55e-12, 3.0 * fi.sigma());
        for s in [1.3e-9, 0.9e-9] {
            let n = 400;
            let dh = (threshold - s) / n as f64;
            let integral: f64 = (0..=n)
                .map(|j| {
                    let w = match j {
                        0 => 1.0,
                        j if j == n => 1.0,
                        j if j % 2 == 1 => 4.0,
                        _ => 2.0,
                    };
                    w * isbl.at(s + j as f64 * dh).unwrap().stiffness
                })
                .sum::<f64>()
                * dh
                / 3.0;
            let f = fi.forces(s, 0.0, a).unwrap();
            assert!(
                (f.contact_force / (a * integral) - 1.0).abs() < 2e-3,
                "s = {s}: {} vs {}",
                f.contact_force,
                a * integral
            );
        }
    }
}
