//! The index page of `lamina demo`: what each stage made, with its figures, and the three jobs
//! (steel, print, audit) as cards of headline figures on the first screen.

use std::fmt::Write as _;

/// One section of the index: a stage or fixture, what it did, its outputs and figures.
pub struct Entry {
    pub name: String,
    pub about: String,
    pub outputs: Vec<String>,
    pub preview: String,
    pub facts: String,
}

/// One of the three jobs lamina exists for, as the index's first screen shows it: its
/// headline figures and where to look.
pub struct Headline {
    pub job: String,
    /// What was made, in a sentence.
    pub what: String,
    pub figures: Vec<(String, String)>,
    pub preview: String,
    /// (label, href) of the viewer pages and reports.
    pub links: Vec<(String, String)>,
}

/// The demo's index.html: the three jobs' cards, then the growth forms and stages, then the
/// first `fixtures` entries (the fixtures read and converted), each with its viewer links.
pub fn index_html(
    jobs: &[Headline],
    entries: &[Entry],
    viewers: &[Vec<(String, String)>],
    fixtures: usize,
) -> String {
    let mut s = String::from(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>lamina demo</title>\n\
         <style>body{font:15px/1.45 system-ui,sans-serif;margin:1.5em auto;max-width:76em;color:#222;padding:0 1em}\
         section{border-top:1px solid #ccc;padding:1em 0;display:flex;gap:2em}\
         section img{width:26em;max-height:26em;object-fit:contain;background:#fff;border:1px solid #ddd}\
         code{background:#f3f3f3;padding:0 .3em}a.view{font-weight:600}\
         .jobs{display:grid;grid-template-columns:repeat(auto-fit,minmax(22em,1fr));gap:1.2em;margin:1em 0 2em}\
         .job{border:1px solid #ccd;border-radius:6px;padding:.8em 1em;background:#fafbfc}\
         .job h2{margin:.1em 0 .3em;font-size:1.25em}.job p{margin:.3em 0}\
         .job img{width:100%;height:12em;object-fit:contain;background:#fff;border:1px solid #e3e3e3}\
         .job table{border-collapse:collapse;width:100%;margin:.4em 0}\
         .job td{padding:1px 4px;border-bottom:1px solid #e8e8e8;vertical-align:top}\
         .job td:last-child{font-weight:600;text-align:right}\
         .job .go a{display:inline-block;margin:.2em .6em .2em 0;font-weight:600}</style></head><body>\n\
         <h1>lamina demo</h1>\n<p>Three jobs lamina does end to end, each from one network, checked by \
         independent validators: steel a fabricator can cut and weld, a resin print, and a planarity \
         audit. Made by <code>lamina demo</code>; growth forms and every fixture below.</p>\n<div class=\"jobs\">\n",
    );
    for j in jobs {
        let _ = write!(
            s,
            "<div class=\"job\"><h2>{}</h2><a href=\"{p}\"><img src=\"{p}\" alt=\"{}\"></a><p>{}</p><table>",
            j.job,
            j.job,
            j.what,
            p = j.preview
        );
        for (k, v) in &j.figures {
            let _ = write!(s, "<tr><td>{k}</td><td>{v}</td></tr>");
        }
        s.push_str("</table><p class=\"go\">");
        for (label, href) in &j.links {
            let _ = write!(s, "<a href=\"{href}\">{label}</a>");
        }
        s.push_str("</p></div>\n");
    }
    s.push_str("</div>\n");
    // The growth forms and the jobs' own stages, then the fixtures read and converted.
    let fixtures = fixtures.min(entries.len());
    let mut all: Vec<(&Entry, &Vec<(String, String)>)> = entries.iter().zip(viewers).collect();
    let read = all.drain(..fixtures).collect::<Vec<_>>();
    for (heading, part) in [
        ("Growth forms and the stages behind the jobs", all),
        ("Fixtures: read, checked, converted to every format", read),
    ] {
        let _ = writeln!(s, "<h2>{heading}</h2>");
        for (e, views) in part {
            entry_html(&mut s, e, views);
        }
    }
    s.push_str("</body></html>\n");
    s
}

fn entry_html(s: &mut String, e: &Entry, views: &[(String, String)]) {
    let _ = write!(
        s,
        "<section><a href=\"{p}\"><img src=\"{p}\" alt=\"{n}\"></a><div><h3>{n}</h3><p>{a}</p><p>{f}</p>",
        p = e.preview,
        n = e.name,
        a = e.about,
        f = e.facts
    );
    if !views.is_empty() {
        let links: Vec<String> = views
            .iter()
            .map(|(label, href)| format!("<a class=\"view\" href=\"{href}\">{label}</a>"))
            .collect();
        let _ = write!(
            s,
            "<p><strong>Look in the viewer:</strong> {}</p>",
            links.join(" · ")
        );
    }
    s.push_str("<ul>");
    for o in &e.outputs {
        let _ = write!(s, "<li><a href=\"{o}\">{o}</a></li>");
    }
    s.push_str("</ul></div></section>\n");
}
