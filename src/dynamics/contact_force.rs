//! How the contact force follows from the contact law (eq. 2.16, §2.2): the reading both the
//! 2-DOF and the 3-DOF models use (docs/model-form.md).

/// Reading of eq. 2.16 (§2.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactForceForm {
    /// `F_c = A_n k_c(s)·(s_c − s) − c_c ṡ`: the contact stiffness times the interference
    /// (faithful to the surviving tokens; default).
    InterferenceTangent,
    /// `F_c = A_n P(s) − c_c ṡ`.
    StaticCurve,
    /// `F_c = A_n [P(s) − P(s_c)] − c_c ṡ = A_n ∫_s^{s_c} k_c(h) dh − c_c ṡ`: the force the
    /// tangent stiffness of eq. 2.16 builds up over the interference, zero at the contact
    /// threshold and continuous there (docs/model-form.md).
    IntegratedStiffness,
}
