//! `hdi report` and the report `hdi run` writes: rendered in a real browser (headless
//! Chromium), every image loads and decodes, every link resolves on disk, the validation
//! table agrees with `hdi validate --json`, a no-op rerun leaves the report alone.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The instances the report tests run: surfaces, the interface and the DMW (figures, HDF5,
/// tables) — quick in a debug build.
const ONLY: &[&str] = &["--only", "hdi", "disk_md"];

/// The project name carries every HTML metacharacter: a TOML value the page shows.
const EVIL_NAME: &str = "study <&\"> 'x'";

fn project(validation: bool) -> Project {
    let p = Project::shipped();
    let text = p.config().replace(
        "name = \"hdi sample study\"",
        "name = \"study <&\\\"> 'x'\"",
    );
    assert!(text.contains("study <&"), "project name not replaced");
    let off = "[report]\nvalidation = false\n";
    assert!(
        text.contains(off),
        "Project::shipped() has no [report] table"
    );
    p.set_config(&text.replace(off, &format!("[report]\nvalidation = {validation}\n")));
    p
}

fn chromium() -> PathBuf {
    let found = std::env::var_os("PATH")
        .into_iter()
        .flat_map(|p| std::env::split_paths(&p).collect::<Vec<_>>())
        .flat_map(|d| ["chromium", "chromium-browser"].map(|n| d.join(n)))
        .find(|p| p.is_file());
    found.expect("chromium not found: run `bash scripts/setup.sh` (installs Debian's chromium)")
}

/// Chromium's arguments for a headless render of a local page (root needs --no-sandbox).
fn headless(profile: &Path) -> Command {
    let mut c = Command::new(chromium());
    c.args([
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--no-first-run",
        "--disable-extensions",
        "--hide-scrollbars",
    ])
    .arg(format!("--user-data-dir={}", profile.display()));
    c
}

fn file_url(p: &Path) -> String {
    format!("file://{}", p.canonicalize().unwrap().display())
}

/// Percent-decoding of a relative URL path (the report encodes every non-unreserved byte).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).unwrap();
            out.push(u8::from_str_radix(hex, 16).unwrap());
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).unwrap()
}

/// The page's images, links, ids and validation rows, parsed from `html` by Python's
/// html.parser (independent of how hdi writes the page).
fn parse_dom(html: &str) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("dom.html");
    std::fs::write(&f, html).unwrap();
    let script = r#"
import json, sys
from html.parser import HTMLParser
class P(HTMLParser):
    def __init__(self):
        super().__init__()
        self.out = {"img": [], "a": [], "ids": [], "rows": [], "body": {}}
        self.row = None
    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a: self.out["ids"].append(a["id"])
        if tag == "body": self.out["body"] = a
        if tag == "img": self.out["img"].append(a.get("src"))
        if tag == "a": self.out["a"].append(a.get("href"))
        if tag == "tr" and "data-pass" in a:
            self.out["rows"].append({"id": a["data-id"], "area": a["data-area"],
                                     "pass": a["data-pass"], "class": a.get("class", "")})
p = P()
p.feed(open(sys.argv[1], encoding="utf-8").read())
print(json.dumps(p.out))
"#;
    let o = Command::new(python())
        .arg("-c")
        .arg(script)
        .arg(&f)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// Every `src`/`href` of a page in `dir` that is not a fragment resolves to an existing file
/// (relative to the page, links followed); returns the image files.
fn assert_links_resolve(dir: &Path, dom: &serde_json::Value) -> Vec<PathBuf> {
    let ids: Vec<&str> = dom["ids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let resolve = |u: &str| -> PathBuf {
        assert!(
            !u.contains("://") && !u.starts_with('/'),
            "not a relative link: {u}"
        );
        dir.join(percent_decode(u))
    };
    let mut n_links = 0;
    for a in dom["a"].as_array().unwrap() {
        let href = a.as_str().expect("an <a> without href");
        if let Some(frag) = href.strip_prefix('#') {
            assert!(ids.contains(&frag), "dangling fragment link {href}");
            continue;
        }
        let p = resolve(href);
        assert!(p.is_file(), "link {href} → {} missing", p.display());
        n_links += 1;
    }
    assert!(n_links > 10, "only {n_links} file links");
    dom["img"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            let s = s.as_str().expect("an <img> without src");
            let p = resolve(s);
            assert!(p.is_file(), "image {s} → {} missing", p.display());
            p
        })
        .collect()
}

/// Decode a PNG; returns (width, height, variance of the 8-bit samples).
fn decode_png(p: &Path) -> (u32, u32, f64) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(p).unwrap()));
    let mut reader = dec
        .read_info()
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader
        .next_frame(&mut buf)
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let data = &buf[..info.buffer_size()];
    let n = data.len() as f64;
    let mean = data.iter().map(|&b| b as f64).sum::<f64>() / n;
    let var = data.iter().map(|&b| (b as f64 - mean).powi(2)).sum::<f64>() / n;
    (info.width, info.height, var)
}

#[test]
fn the_report_renders_in_chromium_with_every_image_and_link_resolving() {
    let p = project(true);
    let o = p.run(&[&["run"], ONLY].concat());
    assert_ok(&o);
    let index = p.processed().join("report").join("index.html");
    assert!(
        stderr(&o).contains("report: ") && index.is_file(),
        "no report: {}",
        stderr(&o)
    );
    let raw = std::fs::read_to_string(&index).unwrap();
    assert!(!raw.contains(EVIL_NAME), "unescaped project name");
    assert!(raw.contains("study &lt;&amp;&quot;&gt; &#39;x&#39;"));

    // The browser renders the page (file://, no network) and its self-check runs.
    let profile = tempfile::tempdir().unwrap();
    let o = headless(profile.path())
        .args(["--dump-dom", "--virtual-time-budget=5000"])
        .arg(file_url(&index))
        .output()
        .expect("running chromium");
    assert!(o.status.success(), "chromium: {}", stderr(&o));
    let dom = parse_dom(&stdout(&o));
    let body = &dom["body"];
    assert_eq!(body["data-broken-images"], "0", "broken images: {body}");
    let n_img: usize = body["data-images"].as_str().unwrap().parse().unwrap();
    assert!(n_img >= 5, "only {n_img} images rendered");
    // The escaped name came back as the original text in the browser's DOM.
    assert!(stdout(&o).contains("study &lt;&amp;\"&gt; 'x'"));

    // Every image and link resolves on disk, and every image decodes.
    let images = assert_links_resolve(index.parent().unwrap(), &dom);
    assert_eq!(images.len(), n_img);
    for img in &images {
        let (w, h, _) = decode_png(img);
        assert!(w > 0 && h > 0, "{}", img.display());
    }

    // The validation table says pass/differs row by row as `hdi validate --json` does.
    let v = p.run(&["validate", "--json"]);
    let j: serde_json::Value = serde_json::from_slice(&v.stdout)
        .unwrap_or_else(|e| panic!("validate --json: {e}: {}", stderr(&v)));
    let mut want = Vec::new();
    for (area, rows) in j["areas"].as_object().unwrap() {
        for r in rows.as_array().unwrap() {
            want.push((
                area.clone(),
                r["id"].as_str().unwrap().to_string(),
                r["pass"].as_bool().unwrap(),
                r["class"].as_str().unwrap().to_string(),
            ));
        }
    }
    let got: Vec<(String, String, bool, String)> = dom["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let pass = r["pass"] == "true";
            let cls = r["class"].as_str().unwrap();
            // The colour class says the same as the pass attribute.
            assert_eq!(cls == "v-pass", pass, "{r}");
            (
                r["area"].as_str().unwrap().to_string(),
                r["id"].as_str().unwrap().to_string(),
                pass,
                cls.to_string(),
            )
        })
        .collect();
    assert!(want.len() > 50, "only {} validation rows", want.len());
    assert_eq!(got.len(), want.len(), "validation rows");
    for ((ga, gi, gp, gc), (wa, wi, wp, wc)) in got.iter().zip(&want) {
        assert_eq!((ga, gi, gp), (wa, wi, wp), "validation row");
        if !wp && gc != "v-not-run" {
            // D rows that miss are `differs`, never a failure colour (a row whose input has
            // not been computed is `not run`, whatever its class).
            assert_eq!(gc == "v-differs", wc == "D", "{gi}: {gc} for class {wc}");
        }
    }

    // A screenshot as a test artefact: a real, non-blank image.
    let artefacts = PathBuf::from(
        std::env::var("CARGO_TARGET_DIR")
            .unwrap_or_else(|_| repo_root().join("target").to_string_lossy().to_string()),
    )
    .join("test-artefacts");
    std::fs::create_dir_all(&artefacts).unwrap();
    let shot = artefacts.join("report.png");
    let _ = std::fs::remove_file(&shot);
    let o = headless(profile.path())
        .arg(format!("--screenshot={}", shot.display()))
        .args(["--window-size=1280,2000", "--virtual-time-budget=5000"])
        .arg(file_url(&index))
        .output()
        .expect("running chromium");
    assert!(o.status.success(), "chromium: {}", stderr(&o));
    let (w, h, var) = decode_png(&shot);
    assert_eq!((w, h), (1280, 2000), "screenshot size");
    assert!(var > 100.0, "blank screenshot (variance {var})");
}

#[test]
fn run_writes_the_report_a_noop_rerun_keeps_it_and_copies_keep_their_links() {
    let p = project(false);
    assert_ok(&p.run(&[&["run"], ONLY].concat()));
    let report = p.processed().join("report");
    let index = report.join("index.html");
    let text = std::fs::read_to_string(&index).unwrap();
    let mtime = std::fs::metadata(&index).unwrap().modified().unwrap();
    // What ran is in the summary; validation is off as configured.
    assert!(
        text.contains("[report] validation = false"),
        "validation not off"
    );
    assert!(text.contains("data-state=\"fresh\"") && text.contains("data-state=\"missing\""));
    assert_links_resolve(&report, &parse_dom(&text));

    // A no-op rerun: the report is neither rebuilt nor touched.
    std::thread::sleep(std::time::Duration::from_millis(1100));
    let o = p.run(&[&["run"], ONLY].concat());
    assert_ok(&o);
    assert!(stderr(&o).contains("report up to date"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&index).unwrap(), text);
    assert_eq!(
        std::fs::metadata(&index).unwrap().modified().unwrap(),
        mtime
    );

    // A run that computes something rebuilds it.
    let o = p.run(&["run", "--only", "disk_md", "--force"]);
    assert_ok(&o);
    assert!(stderr(&o).contains("report: "), "{}", stderr(&o));
    assert_ne!(std::fs::read_to_string(&index).unwrap(), text);

    // processed/ copied as a whole (links kept): the copy's report still resolves.
    let copy = p.path().join("copied");
    let o = Command::new("cp")
        .arg("-a")
        .arg(p.processed())
        .arg(&copy)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let copied = copy.join("report");
    let dom = parse_dom(&std::fs::read_to_string(copied.join("index.html")).unwrap());
    let copy_real = copy.canonicalize().unwrap();
    for img in assert_links_resolve(&copied, &dom) {
        let real = img.canonicalize().unwrap();
        assert!(
            real.starts_with(&copy_real),
            "{} leaves the copy",
            real.display()
        );
    }

    // `hdi report --out` elsewhere links back into processed/.
    let elsewhere = p.path().join("elsewhere").join("rep");
    let o = p.run(&[
        "report",
        "--out",
        elsewhere.to_str().unwrap(),
        "--no-validation",
    ]);
    assert_ok(&o);
    let dom = parse_dom(&std::fs::read_to_string(elsewhere.join("index.html")).unwrap());
    assert!(!assert_links_resolve(&elsewhere, &dom).is_empty());

    // `[report] enabled = false`: no report at the end of a run.
    p.set_config(&p.config().replace(
        "[report]\nvalidation = false\n",
        "[report]\nenabled = false\nvalidation = false\n",
    ));
    std::fs::remove_dir_all(&report).unwrap();
    let o = p.run(&["run", "--only", "disk_md", "--force"]);
    assert_ok(&o);
    assert!(!report.exists(), "report written although disabled");
}
