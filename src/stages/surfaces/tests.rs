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

/// `x3p = true` writes the analysed map as X3P that SurfaceTopography opens with hdi's heights:
/// its reading (`tests/data/surfaces/x3p_out/make_reference.py`) of the file hdi wrote is
/// compared with the map, and that file's members are what the writer writes today.
#[test]
fn x3p_out_opens_in_surfacetopography_with_the_analysed_heights() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = root.join("tests/data/surfaces/x3p_out");
    let c = cfg("x3p = true\ncrop = { x0 = \"11.8 um\", y0 = \"78.69 um\", \
         width = \"12.59 um\", height = \"12.59 um\" }");
    let p = check(&c, root.join("tests/data/surfaces/opd-1.opd")).unwrap();
    assert_eq!(p.canonical()["x3p"], true);
    let a = analyse(&p).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    write_x3p(&a, &p, &tmp.path().join("s.x3p")).unwrap();
    let fresh = std::fs::read(tmp.path().join("s.x3p")).unwrap();
    let committed = std::fs::read(dir.join("opd-1_crop.x3p")).unwrap();
    let (fresh, committed) = (
        crate::formats::zip::ZipArchive::parse(&fresh).unwrap(),
        crate::formats::zip::ZipArchive::parse(&committed).unwrap(),
    );
    let names = |z: &crate::formats::zip::ZipArchive| -> Vec<String> {
        z.entries().iter().map(|e| e.name.clone()).collect()
    };
    assert_eq!(names(&fresh), names(&committed));
    for e in committed.entries() {
        let got = fresh.read(fresh.find(&e.name).unwrap(), 1 << 24).unwrap();
        assert!(got == committed.read(e, 1 << 24).unwrap(), "{}", e.name);
    }

    let want: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("surfacetopography_reading.json")).unwrap(),
    )
    .unwrap();
    let map = a.final_map();
    let f = |k: &str| want[k].as_f64().unwrap();
    assert_eq!((map.nx() as f64, map.ny() as f64), (f("nx"), f("ny")));
    let rel = |a: f64, b: f64| ((a - b) / b).abs();
    assert!(rel(map.dx * map.nx() as f64, f("size_x_m")) < 1e-12);
    assert!(rel(map.dy * map.ny() as f64, f("size_y_m")) < 1e-12);
    let valid = map.valid.as_ref().unwrap();
    let mut undefined: Vec<[usize; 2]> = valid
        .indexed_iter()
        .filter(|(_, ok)| !**ok)
        .map(|((y, x), _)| [x, y])
        .collect();
    undefined.sort();
    let listed: Vec<[usize; 2]> = serde_json::from_value(want["undefined"].clone()).unwrap();
    assert_eq!(undefined, listed);
    let z: Vec<f64> = map
        .z
        .iter()
        .zip(valid)
        .filter(|v| *v.1)
        .map(|v| *v.0)
        .collect();
    let mean = z.iter().sum::<f64>() / z.len() as f64;
    let rms = (z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / z.len() as f64).sqrt();
    assert!(rel(rms, f("rms_height_m")) < 1e-9, "{rms}");
    for px in want["pixels_m"].as_array().unwrap() {
        let (x, y) = (px[0].as_u64().unwrap(), px[1].as_u64().unwrap());
        assert_eq!(map.z[[y as usize, x as usize]], px[2].as_f64().unwrap());
    }
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
