use super::*;

fn cfg(text: &str) -> SurfaceConfig {
    toml::from_str(text).unwrap()
}

#[test]
fn crops_and_files_make_every_area_and_one_area_keeps_the_old_key() {
    let one = cfg("file = \"a.gwy\"\ncrop = { x0 = 0, y0 = 0, width = 1e-6, height = 1e-6 }");
    let p = check(&one, "a.gwy".into()).unwrap();
    assert_eq!(p.areas.len(), 1);
    // No `areas` entry: the cache key and the HDF5 parameters of a single scan are as before.
    assert!(p.canonical().get("areas").is_none());
    assert_eq!(p.canonical(), p.canonical_one());

    let two = cfg(
        "crops = [{ x0 = 0, y0 = 0, width = 1e-6, height = 1e-6 },\n\
             { x0 = 1e-6, y0 = 0, width = 1e-6, height = 1e-6 }]",
    );
    let p = check_files(&two, vec!["a.gwy".into(), "b.gwy".into(), "c.gwy".into()]).unwrap();
    assert_eq!(p.areas.len(), 6);
    assert_eq!(p.areas[3].file, PathBuf::from("b.gwy"));
    assert_eq!(p.areas[3].crop.unwrap().x0, 1e-6);
    assert_eq!(p.distinct_files().len(), 3);
    assert_eq!(p.canonical()["areas"].as_array().unwrap().len(), 6);
    assert_eq!(p.area(5).areas.len(), 1);
    assert_eq!(p.area(5).file, PathBuf::from("c.gwy"));

    let both = cfg("crop = { x0 = 0, y0 = 0, width = 1e-6, height = 1e-6 }\n\
             crops = [{ x0 = 0, y0 = 0, width = 1e-6, height = 1e-6 }]");
    let e = check(&both, "a".into()).unwrap_err();
    assert_eq!(e.key, "crops");
    let empty = cfg("crops = []");
    assert!(check(&empty, "a".into()).is_err());
    assert!(check_files(&empty, vec![]).is_err());
}

#[test]
fn tip_radius_enters_the_key_only_when_given() {
    let without = check(&cfg("file = \"a.gwy\""), "a.gwy".into()).unwrap();
    assert!(without.canonical().get("tip_radius_m").is_none());
    let with = check(
        &cfg("file = \"a.gwy\"\ntip_radius = \"40 nm\""),
        "a.gwy".into(),
    )
    .unwrap();
    assert_eq!(with.tip_radius, Some(40e-9));
    assert_eq!(with.canonical()["tip_radius_m"], serde_json::json!(40e-9));
    let mut rest = with.canonical();
    rest.as_object_mut().unwrap().remove("tip_radius_m");
    assert_eq!(rest, without.canonical());
    let e = check(&cfg("tip_radius = \"-1 nm\""), "a".into()).unwrap_err();
    assert_eq!(e.key, "tip_radius");
    assert!(toml::from_str::<SurfaceConfig>("tip_radius_nm = 40").is_err());
}
