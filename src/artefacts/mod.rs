//! What one stage hands another, defined once: each file here is the typed form of an
//! artefact a producing stage writes (its `result.json` or an HDF5 file in its outputs) and a
//! consuming stage reads from its upstream results. Producer and consumer share the struct,
//! the dataset names and the file names, so neither imports the other's stage file.
pub mod analysis;
pub mod bulge;
pub mod calibration;
pub mod cases;
pub mod contact;
pub mod contact_bem;
pub mod dmw_tracks;
pub mod doe;
pub mod interface;
pub mod ldv;
pub mod ordered;
pub mod series;
pub mod simulate;
pub mod surface;
pub mod three_dof;

/// The result of the upstream `kind` instance `name`, read through `T`, the type that kind
/// writes; a missing instance or a result that does not parse as `T` is an error naming it.
pub fn upstream_result<T: serde::de::DeserializeOwned>(
    upstream: &std::collections::BTreeMap<String, serde_json::Value>,
    kind: &'static str,
    name: &str,
) -> crate::error::Result<T> {
    let result = upstream
        .get(name)
        .ok_or_else(|| crate::error::Error::MissingUpstream {
            kind,
            name: name.to_string(),
        })?;
    T::deserialize(result).map_err(|e| crate::error::Error::UpstreamField {
        kind,
        name: name.to_string(),
        what: format!("readable result ({e})"),
    })
}

/// A value a result may leave undefined (no summits, a flat map): `None` unless finite, so it
/// is written as `null` (JSON has no NaN; docs/json.md) and reads back as `None`.
pub fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}
