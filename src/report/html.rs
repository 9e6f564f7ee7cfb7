//! The report page: one self-contained HTML file (inline CSS, no fonts or scripts from the
//! network, a small inline script only as a self-check). Every string from a file name, the
//! pipeline file or a result goes through [`esc`].

use super::{Instance, Page};
use crate::validation::{class_counts, ledger, Row};
use serde_json::Value;
use std::fmt::Write;

/// HTML-escape text for element content and quoted attribute values.
pub(crate) fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// The unit a column or key name carries in its suffix, written for people (`um^2` → `µm²`);
/// `""` for none. The suffixes are the tables' own (`core::store::unit_of_column`,
/// docs/tables.md); statistic suffixes after the unit (`sigma_nm_mean`, `…_ci95_low`) are
/// looked through.
pub(crate) fn unit_of(name: &str) -> String {
    const STATS: &[&str] = &["mean", "std", "low", "high", "min", "max", "median", "se"];
    let mut parts: Vec<&str> = name.split('_').collect();
    while parts.len() > 1 && STATS.contains(parts.last().unwrap_or(&"")) {
        parts.pop();
        if parts.last() == Some(&"ci95") {
            parts.pop();
        }
    }
    let Some(unit) = crate::core::store::unit_of_column(&parts.join("_")) else {
        return String::new();
    };
    // ASCII `u` for micro and `^2` (as UDUNITS writes them) in typographic form.
    unit.split('/')
        .map(|u| match u.strip_prefix('u') {
            Some(rest) if rest.starts_with(|c: char| c.is_ascii_alphabetic()) => format!("µ{rest}"),
            _ => u.to_string(),
        })
        .collect::<Vec<_>>()
        .join("/")
        .replace("^2", "²")
}

/// A number for people: six significant digits, scientific when very small or large.
pub(crate) fn num(x: f64) -> String {
    if !x.is_finite() {
        return "–".into();
    }
    let a = x.abs();
    if x == 0.0 {
        "0".into()
    } else if !(1e-3..1e7).contains(&a) {
        format!("{x:.5e}")
    } else {
        let digits = (5 - a.log10().floor() as i32).clamp(0, 9) as usize;
        let s = format!("{x:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

fn value_text(v: &Value) -> String {
    match v {
        Value::Null => "–".into(),
        Value::Number(n) => n.as_f64().map(num).unwrap_or_else(|| n.to_string()),
        Value::String(s) => s.clone(),
        Value::Bool(b) => b.to_string(),
        other => other.to_string(),
    }
}

fn secs(x: f64) -> String {
    if x < 10.0 {
        format!("{x:.2} s")
    } else if x < 600.0 {
        format!("{x:.1} s")
    } else {
        format!("{:.0} min {:.0} s", (x / 60.0).floor(), x % 60.0)
    }
}

fn bytes(n: u64) -> String {
    if n < 10_000 {
        format!("{n} B")
    } else if n < 10_000_000 {
        format!("{:.0} kB", n as f64 / 1e3)
    } else {
        format!("{:.0} MB", n as f64 / 1e6)
    }
}

const CSS: &str = "
body{font:14px/1.45 system-ui,-apple-system,'Segoe UI',sans-serif;margin:0;color:#1d232b;background:#fafbfc}
main{max-width:1200px;margin:0 auto;padding:0 20px 60px}
header{background:#23395d;color:#fff;padding:18px 20px}
header h1{margin:0;font-size:22px;font-weight:600}header p{margin:4px 0 0;opacity:.85}
nav{position:sticky;top:0;background:#eef1f5;border-bottom:1px solid #d6dbe2;padding:6px 20px;z-index:2}
nav a{margin-right:16px;color:#23395d;text-decoration:none;font-weight:600}
h2{margin-top:34px;border-bottom:2px solid #23395d;padding-bottom:4px}
h3{margin:0 0 6px;font-size:16px}
table{border-collapse:collapse;margin:8px 0;font-size:13px}
th,td{border:1px solid #d6dbe2;padding:3px 7px;text-align:left;vertical-align:top}
th{background:#eef1f5}td.n{text-align:right;font-variant-numeric:tabular-nums}
code,.mono{font-family:ui-monospace,'DejaVu Sans Mono',monospace;font-size:12px;word-break:break-all}
#validation-table code,.numbers code{white-space:nowrap;word-break:normal}
.inst{background:#fff;border:1px solid #d6dbe2;border-radius:6px;padding:12px 14px;margin:14px 0}
.figs{display:flex;flex-wrap:wrap;gap:10px}
figure{margin:0;max-width:370px}figure img{max-width:100%;border:1px solid #d6dbe2;background:#fff}
figcaption{font-size:12px;color:#555}
.files{columns:3;font-size:12px;margin:6px 0;padding-left:18px}
.tag{display:inline-block;padding:0 6px;border-radius:3px;font-size:12px;font-weight:600}
.s-fresh,.o-ran,.o-cached,.v-pass{background:#d9f2dc;color:#155d22}
.o-cached{background:#e4ebf5;color:#23395d}
.s-stale,.s-missing,.v-differs,.v-no{background:#fdf0cf;color:#7a5200}
.o-failed,.o-skipped,.v-fail{background:#fbdada;color:#8a1c1c}
tr.v-pass td.st{background:#d9f2dc}tr.v-differs td.st,tr.v-no td.st{background:#fdf0cf}
tr.v-fail td.st{background:#fbdada}tr.v-not-run td.st{background:#e4ebf5;color:#23395d}
.banner{padding:6px 10px;border-radius:4px;margin:10px 0;background:#eef1f5}
.banner.ok{background:#d9f2dc}.banner.bad{background:#fbdada}
.muted{color:#667}
";

/// A self-check, as progressive enhancement: counts the figures that did not load and says
/// so in `data-broken-images` and a banner (the page reads the same without it).
const SCRIPT: &str = "window.addEventListener('load',function(){var im=document.images,b=0;\
for(var i=0;i<im.length;i++){if(!im[i].complete||im[i].naturalWidth===0){b++;im[i].setAttribute('data-broken','1');}}\
document.body.setAttribute('data-broken-images',String(b));\
document.body.setAttribute('data-images',String(im.length));\
var s=document.getElementById('selfcheck');\
s.textContent=b?(b+' of '+im.length+' figures failed to load'):('all '+im.length+' figures loaded');\
s.className=b?'banner bad':'banner ok';});";

pub(crate) fn render(p: &Page) -> String {
    let mut h = String::new();
    let title = if p.project.is_empty() {
        "hdi report".to_string()
    } else {
        format!("hdi report — {}", p.project)
    };
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width,initial-scale=1\">\
         <meta name=\"generator\" content=\"hdi {ver}\"><title>{t}</title><style>{CSS}</style></head>\n\
         <body data-broken-images=\"unchecked\" data-report-key=\"{key}\">\n\
         <header><h1>{t}</h1><p>{cfg} · hdi {ver} · report generated {gen}</p></header>\n\
         <nav><a href=\"#summary\">Summary</a><a href=\"#instances\">Stage instances</a>\
         <a href=\"#validation\">Validation</a><a href=\"#provenance\">Provenance</a>\
         <a href=\"#status\">Status</a></nav>\n<main>\n\
         <p id=\"selfcheck\" class=\"banner\">{n} figures (the self-check needs JavaScript)</p>\n",
        t = esc(&title),
        ver = esc(&p.hdi_version),
        key = esc(&p.key),
        cfg = esc(&p.config_name),
        gen = esc(&p.generated),
        n = p.instances.iter().map(|i| i.figures.len()).sum::<usize>(),
    );
    summary(&mut h, p);
    instances(&mut h, p);
    validation(&mut h, p);
    provenance(&mut h, p);
    status(&mut h, p);
    let _ = write!(h, "</main>\n<script>{SCRIPT}</script>\n</body></html>\n");
    h
}

fn summary(h: &mut String, p: &Page) {
    h.push_str("<h2 id=\"summary\">Summary</h2>\n");
    match &p.run {
        Some(r) => {
            let count = |o: &str| r.instances.iter().filter(|i| i.outcome == o).count();
            let _ = writeln!(
                h,
                "<p>Last run that changed something: finished <b>{}</b> with hdi {} on {} \
                 thread(s) in <b>{}</b>: <span class=\"tag o-ran\">ran {}</span> \
                 <span class=\"tag o-cached\">cached {}</span> \
                 <span class=\"tag o-failed\">failed {}</span> \
                 <span class=\"tag o-skipped\">skipped {}</span> of {} instances.</p>",
                esc(&r.finished),
                esc(&r.hdi_version),
                r.jobs,
                secs(r.wall_time_s),
                count("ran"),
                count("cached"),
                count("failed"),
                count("skipped"),
                r.instances.len()
            );
        }
        None => h.push_str(
            "<p class=\"muted\">No record of an <code>hdi run</code> in this processed \
             directory: outcomes of the last run are not shown.</p>\n",
        ),
    }
    h.push_str(
        "<table id=\"summary-table\"><tr><th>instance</th><th>kind</th><th>state</th>\
         <th>last run</th><th>wall time</th><th>computed</th><th>figures</th><th>files</th></tr>\n",
    );
    for (i, inst) in p.instances.iter().enumerate() {
        let (outcome, msg) = inst
            .last_run
            .as_ref()
            .map(|r| (r.outcome.as_str(), r.message.as_str()))
            .unwrap_or(("", ""));
        let wall = inst
            .manifest
            .as_ref()
            .map(|m| secs(m.wall_time_s))
            .unwrap_or_default();
        let created = inst
            .manifest
            .as_ref()
            .map(|m| m.created.clone())
            .unwrap_or_default();
        let _ = writeln!(
            h,
            "<tr><td><a href=\"#inst-{i}\">{}</a></td><td>{}</td>\
             <td><span class=\"tag s-{}\">{}</span></td><td>{}</td><td class=\"n\">{}</td>\
             <td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td></tr>",
            esc(&inst.name),
            esc(&inst.kind),
            esc(&inst.state),
            esc(&inst.state),
            if outcome.is_empty() {
                String::new()
            } else {
                format!(
                    "<span class=\"tag o-{o}\" title=\"{m}\">{o}</span>",
                    o = esc(outcome),
                    m = esc(msg)
                )
            },
            wall,
            esc(&created),
            inst.figures.len(),
            inst.files.len()
        );
    }
    let total: f64 = p
        .instances
        .iter()
        .filter_map(|i| i.manifest.as_ref())
        .map(|m| m.wall_time_s)
        .sum();
    let _ = writeln!(
        h,
        "</table>\n<p class=\"muted\">Wall time: how long the instance's current entry took \
         when it was computed (from its manifest.json; {} for all current entries together, \
         some of them in parallel); cached instances took no time in the last run.</p>",
        secs(total)
    );
    if !p.tables.is_empty() {
        h.push_str("<h3>Summary tables</h3><ul class=\"files\">\n");
        for (href, name) in &p.tables {
            let _ = writeln!(h, "<li><a href=\"{}\">{}</a></li>", esc(href), esc(name));
        }
        h.push_str("</ul>\n");
    }
}

fn instances(h: &mut String, p: &Page) {
    h.push_str("<h2 id=\"instances\">Stage instances</h2>\n");
    for (i, inst) in p.instances.iter().enumerate() {
        let _ = writeln!(
            h,
            "<section class=\"inst\" id=\"inst-{i}\"><h3>{} <span class=\"muted\">[{}]</span> \
             <span class=\"tag s-{}\">{}</span></h3>",
            esc(&inst.name),
            esc(&inst.kind),
            esc(&inst.state),
            esc(&inst.state)
        );
        if let Some(m) = &inst.manifest {
            let _ = writeln!(
                h,
                "<p class=\"muted\">entry <code>{}</code> computed {} in {} by hdi {}</p>",
                esc(&inst.key),
                esc(&m.created),
                secs(m.wall_time_s),
                esc(&m.hdi_version)
            );
        }
        if !inst.why.is_empty() {
            let _ = writeln!(h, "<p class=\"muted\">{}</p>", esc(&inst.why.join("; ")));
        }
        if let Some(r) = &inst.last_run {
            if !r.message.is_empty() {
                let _ = writeln!(
                    h,
                    "<p class=\"banner bad\">last run: {}: {}</p>",
                    esc(&r.outcome),
                    esc(&r.message)
                );
            }
        }
        instance_body(h, inst);
        h.push_str("</section>\n");
    }
}

fn instance_body(h: &mut String, inst: &Instance) {
    if !inst.numbers.is_empty() {
        h.push_str(
            "<table class=\"numbers\"><tr><th>quantity</th><th>value</th><th>unit</th></tr>\n",
        );
        for (k, v) in &inst.numbers {
            let n = matches!(v, Value::Number(_));
            let _ = writeln!(
                h,
                "<tr><td><code>{}</code></td><td{}>{}</td><td>{}</td></tr>",
                esc(k),
                if n { " class=\"n\"" } else { "" },
                esc(&value_text(v)),
                esc(&unit_of(k))
            );
        }
        h.push_str("</table>\n");
    }
    if !inst.figures.is_empty() {
        h.push_str("<div class=\"figs\">\n");
        for (href, name) in &inst.figures {
            let _ = writeln!(
                h,
                "<figure><a href=\"{href}\"><img src=\"{href}\" alt=\"{name}\"></a>\
                 <figcaption>{name}</figcaption></figure>",
                href = esc(href),
                name = esc(name)
            );
        }
        h.push_str("</div>\n");
    }
    if !inst.files.is_empty() {
        h.push_str("<ul class=\"files\">\n");
        for (href, name, n) in &inst.files {
            let _ = writeln!(
                h,
                "<li><a href=\"{}\">{}</a> <span class=\"muted\">{}</span></li>",
                esc(href),
                esc(name),
                bytes(*n)
            );
        }
        h.push_str("</ul>\n");
    } else if inst.manifest.is_none() {
        h.push_str("<p class=\"muted\">No current output: run <code>hdi run</code>.</p>\n");
    }
}

/// The row's status word, as `hdi validate` prints it: pass, differs (D), no (Q), FAIL.
/// The row's CSS class and status word (`Row::verdict`).
fn verdict(r: &Row) -> (String, &'static str) {
    let word = r.verdict();
    (format!("v-{}", word.to_lowercase().replace(' ', "-")), word)
}

fn validation(h: &mut String, p: &Page) {
    h.push_str("<h2 id=\"validation\">Validation</h2>\n");
    let Some(v) = &p.validation else {
        h.push_str(
            "<p class=\"muted\">Not included (<code>[report] validation = false</code>): run \
             <code>hdi validate</code>, or <code>hdi report --validation</code>.</p>\n",
        );
        return;
    };
    let all: Vec<&Row> = v
        .areas
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok())
        .flatten()
        .collect();
    h.push_str("<ul id=\"validation-ledger\">\n");
    for line in ledger(all.iter().copied()).lines() {
        let _ = writeln!(h, "<li>{}</li>", esc(&line));
    }
    h.push_str("</ul>\n");
    h.push_str(
        "<p>The published targets (docs/validation.md): G and K rows must pass, D rows \
         depend on inputs the dissertation does not give (shown before and after \
         calibration), Q rows assert an ordering, C rows are consistency checks.</p>\n\
         <table id=\"validation-classes\"><tr><th>class</th><th>rows</th><th>pass</th>\
         <th>not pass</th></tr>\n",
    );
    for (c, n, pass) in class_counts(all.iter().copied()) {
        let _ = writeln!(
            h,
            "<tr data-class=\"{c}\"><td>{c}</td><td class=\"n\">{n}</td><td class=\"n\">{pass}</td>\
             <td class=\"n\">{}</td></tr>",
            n - pass,
            c = c.label()
        );
    }
    h.push_str(
        "</table>\n<table id=\"validation-table\"><tr><th>status</th><th>id</th>\
                <th>class</th><th>basis</th><th>reference</th><th>quantity</th><th>target</th>\
                <th>value</th><th>synthetic record</th><th>calibrated</th><th>tolerance</th>\
                <th>origin / note</th></tr>\n",
    );
    for (area, rows) in &v.areas {
        let _ = writeln!(
            h,
            "<tr class=\"area\"><th colspan=\"12\">{}</th></tr>",
            esc(area)
        );
        match rows {
            Err(e) => {
                let _ = writeln!(
                    h,
                    "<tr class=\"area-error\"><td colspan=\"12\" class=\"banner bad\">{}</td></tr>",
                    esc(e)
                );
            }
            Ok(rows) => {
                for r in rows {
                    let (cls, word) = verdict(r);
                    let c = r.cells(num);
                    let unit = c.unit.as_ref().map_or(String::new(), |u| format!(" [{u}]"));
                    let _ = writeln!(
                        h,
                        "<tr class=\"{cls}\" data-id=\"{id}\" data-area=\"{area}\" data-pass=\"{pass}\">\
                         <td class=\"st\">{word}</td><td><code>{id}</code></td><td>{class}</td>\
                         <td title=\"{basis_detail}\">{basis}</td>\
                         <td>{reference}</td><td>{quantity}{unit}</td><td class=\"n\">{target}</td>\
                         <td class=\"n\">{value}</td><td class=\"n\">{record}</td>\
                         <td class=\"n\">{cal}</td><td>{tol}</td><td>{tail}</td></tr>",
                        id = esc(&r.id),
                        area = esc(area),
                        pass = r.pass(),
                        class = r.class.label(),
                        basis = esc(&c.basis),
                        basis_detail = esc(r.basis.detail()),
                        record = esc(&c.record),
                        reference = esc(&r.reference),
                        quantity = esc(&r.quantity),
                        unit = esc(&unit),
                        target = esc(&c.target),
                        value = esc(&c.value),
                        cal = esc(&c.calibrated),
                        tol = esc(&c.tolerance),
                        tail = esc(&c.notes),
                    );
                }
            }
        }
    }
    h.push_str("</table>\n");
}

fn provenance(h: &mut String, p: &Page) {
    let _ = writeln!(
        h,
        "<h2 id=\"provenance\">Provenance</h2>\n<table><tr><th>hdi version</th><td>{}</td></tr>\
         <tr><th>pipeline file</th><td><code>{}</code> blake3 <code>{}</code></td></tr>\
         <tr><th>report key</th><td><code>{}</code></td></tr></table>",
        esc(&p.hdi_version),
        esc(&p.config_name),
        esc(&p.config_blake3),
        esc(&p.key)
    );
    h.push_str(
        "<table id=\"provenance-table\"><tr><th>instance</th><th>model version</th>\
         <th>cache key</th><th>inputs (role, path, blake3)</th><th>upstream (name, key)</th>\
         <th>computed by</th></tr>\n",
    );
    for inst in &p.instances {
        let inputs = inst
            .inputs
            .iter()
            .map(|(role, path, b)| {
                format!(
                    "{}: <code>{}</code> <code>{}</code>",
                    esc(role),
                    esc(path),
                    esc(b)
                )
            })
            .collect::<Vec<_>>()
            .join("<br>");
        let upstream = inst
            .upstream
            .iter()
            .map(|(n, k)| format!("{} <code>{}</code>", esc(n), esc(k)))
            .collect::<Vec<_>>()
            .join("<br>");
        let by = inst
            .manifest
            .as_ref()
            .map(|m| format!("hdi {}", esc(&m.hdi_version)))
            .unwrap_or_default();
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td><code>{}</code></td><td><code>{}</code></td><td>{}</td>\
             <td>{}</td><td>{}</td></tr>",
            esc(&inst.name),
            esc(&inst.model_version),
            esc(&inst.key),
            inputs,
            upstream,
            by
        );
    }
    h.push_str("</table>\n");
}

fn status(h: &mut String, p: &Page) {
    h.push_str(
        "<h2 id=\"status\">Status</h2>\n<p>As <code>hdi status</code> saw it when the report \
         was written.</p>\n<table id=\"status-table\"><tr><th>state</th><th>instance</th>\
         <th>why</th></tr>\n",
    );
    for inst in &p.instances {
        let _ = writeln!(
            h,
            "<tr data-name=\"{n}\" data-state=\"{s}\"><td><span class=\"tag s-{s}\">{s}</span></td>\
             <td>{n}</td><td>{}</td></tr>",
            esc(&inst.why.join("; ")),
            n = esc(&inst.name),
            s = esc(&inst.state)
        );
    }
    h.push_str("</table>\n");
}
