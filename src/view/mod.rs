//! The offline browser viewer: one self-contained HTML page that turns a lamina file round in
//! 3D (orbit, pan, zoom, fit; colour by a figure with a legend in its unit; hover or click a
//! panel, plate, member, node or weld for its id and figures; a search box that flies to a tag),
//! lays cut sheets out in 2D, and steps through print layers with their islands marked.
//!
//! A [`Scene`] is what the page shows; `pack` builds scenes from the stages' files. The page
//! embeds three.js (vendored under `assets/`, pinned, see `assets/VENDOR.md`), the viewer's
//! own script and the scene as JSON, with geometry as base64 little-endian arrays, and opens
//! with no network access. The reports of `planarize`, `audit`, `size` and `plates` embed the
//! same viewer with [`embed`].
//!
//! What the page guarantees (and `validators/check_viewer.py` checks in headless Chromium):
//! `document.body.dataset.ready` is set once the first frame is drawn; `#select=ID` in the URL
//! (or the search box) selects the object or sheet part with that id, and the element
//! `#lamina-info` then shows its id and figures; `#view=3d|sheets|print` and `#layer=K` pick
//! the tab and the print layer.

pub mod flat;
pub mod pack;
pub mod scene;

use base64::Engine as _;
use glam::DVec3;

use crate::text::html;

/// The three.js release vendored under `assets/`.
pub const THREE_VERSION: &str = "0.185.1";

/// The most triangles, segments or points a scene takes (the page stays under ~150 MB and
/// opens in seconds); larger inputs are refused with a note to simplify them first.
pub const MAX_ELEMENTS: usize = 4_000_000;

const THREE_CORE: &str = include_str!("assets/three.core.min.js");
const THREE_MODULE: &str = include_str!("assets/three.module.min.js");
const ORBIT_CONTROLS: &str = include_str!("assets/OrbitControls.js");
const THREE_LICENSE: &str = include_str!("assets/LICENSE-three.txt");
const VIEWER_JS: &str = include_str!("assets/viewer.js");
const VIEWER_CSS: &str = include_str!("assets/viewer.css");

/// Everything one page shows.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Scene {
    pub title: String,
    /// Said above the view: what was read, what was left out and why.
    pub notes: Vec<String>,
    /// Subtracted from every 3D position before it is stored as f32 (so sub-micron detail
    /// survives coordinates in the kilometres); the figures are written in the original ones.
    pub origin: [f64; 3],
    pub layers: Vec<Layer>,
    pub sheets: Vec<Sheet>,
    pub print: Option<Print>,
}

/// What a 3D layer draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// Triangles, three indices each.
    Faces,
    /// Segments, two indices each.
    Lines,
    /// Points (nodes, weld markers), one per position.
    Points,
}

/// A 3D layer: one kind of thing (panels, plates, members, nodes, welds), each object a run of
/// its elements.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Layer {
    pub name: String,
    pub kind: Kind,
    /// f32 x, y, z per vertex, less the scene's origin, base64.
    pub positions: String,
    /// u32 per index, base64 (empty for points).
    pub indices: String,
    /// u32 segment pairs drawn dark over faces (plate and panel outlines), base64.
    pub outline: String,
    /// The names of the objects' figures, in the order the info panel lists them.
    pub columns: Vec<String>,
    pub objects: Vec<Object>,
    /// Ways to colour the objects; the first is shown first. None: one colour.
    pub colorings: Vec<Coloring>,
    /// Shown when the page opens (the others behind a checkbox).
    pub visible: bool,
}

/// One selectable thing. The page finds where it is from its elements' vertices.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Object {
    pub id: String,
    /// Its first element and how many (triangles, segments or points).
    pub first: u32,
    pub count: u32,
    /// Per column of its layer, the figure's value with its unit ("" where it has none).
    pub values: Vec<String>,
}

/// Object colours by one figure.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Coloring {
    pub name: String,
    /// The unit shown on the legend ("mm", "°", "" for ratios).
    pub unit: String,
    /// What the figure is, under the legend.
    pub definition: String,
    /// Per object: its value (None: no value, drawn grey). Categories: an index into `labels`.
    pub values: Vec<Option<f64>>,
    /// Non-empty for categories: the name of each value.
    pub labels: Vec<String>,
    /// Per label, its fixed colour (`#rrggbb`) where the categories are classes that must look
    /// the same on every model; empty: the palette in label order.
    pub colors: Vec<String>,
    /// A limit marked on the legend (a tolerance, utilisation 1): the scale runs green to red
    /// from 0 to it, and beyond it stays red.
    pub limit: Option<f64>,
}

impl Coloring {
    /// A continuous scale.
    pub fn scale(name: &str, unit: &str, definition: &str, values: Vec<Option<f64>>) -> Self {
        Coloring {
            name: name.into(),
            unit: unit.into(),
            definition: definition.into(),
            values,
            labels: Vec::new(),
            colors: Vec::new(),
            limit: None,
        }
    }

    /// Categories: each object's label; the legend lists them in natural order (numbers in
    /// labels by value: group 2 before group 10).
    pub fn categories(name: &str, definition: &str, of: &[String]) -> Self {
        let mut labels: Vec<String> = of.to_vec();
        labels.sort_by(|a, b| natural_order(a, b));
        labels.dedup();
        let values = of
            .iter()
            .map(|l| {
                labels
                    .binary_search_by(|x| natural_order(x, l))
                    .ok()
                    .map(|k| k as f64)
            })
            .collect();
        Coloring {
            name: name.into(),
            unit: String::new(),
            definition: definition.into(),
            values,
            labels,
            colors: Vec::new(),
            limit: None,
        }
    }

    /// Fixed classes, each with its colour, listed in this order on every model (those no
    /// object falls in too); each object's class by index (None: grey, no class).
    pub fn classes(
        name: &str,
        definition: &str,
        classes: &[(&str, &str)],
        of: &[Option<usize>],
    ) -> Self {
        Coloring {
            name: name.into(),
            unit: String::new(),
            definition: definition.into(),
            values: of
                .iter()
                .map(|k| k.filter(|&k| k < classes.len()).map(|k| k as f64))
                .collect(),
            labels: classes.iter().map(|c| c.0.to_string()).collect(),
            colors: classes.iter().map(|c| c.1.to_string()).collect(),
            limit: None,
        }
    }
}

/// Whether a check holds: the two classes and their colours.
pub const PASS_FAIL: [(&str, &str); 2] = [("within", "#2ca02c"), ("above", "#d62728")];

/// Strings compared with their runs of digits as numbers ("group 2" < "group 10").
fn natural_order(a: &str, b: &str) -> std::cmp::Ordering {
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    loop {
        match (a.first(), b.first()) {
            (None, None) => return std::cmp::Ordering::Equal,
            (None, _) => return std::cmp::Ordering::Less,
            (_, None) => return std::cmp::Ordering::Greater,
            (Some(x), Some(y)) if x.is_ascii_digit() && y.is_ascii_digit() => {
                let run = |s: &[u8]| s.iter().take_while(|c| c.is_ascii_digit()).count();
                let (na, nb) = (run(a), run(b));
                let trim = |s: &[u8]| {
                    let z = s.iter().take_while(|&&c| c == b'0').count();
                    s[z.min(s.len().saturating_sub(1))..].to_vec()
                };
                let (da, db) = (trim(&a[..na]), trim(&b[..nb]));
                let by_value = da.len().cmp(&db.len()).then_with(|| da.cmp(&db));
                if by_value != std::cmp::Ordering::Equal {
                    return by_value;
                }
                let by_zeros = na.cmp(&nb);
                if by_zeros != std::cmp::Ordering::Equal {
                    return by_zeros;
                }
                a = &a[na..];
                b = &b[nb..];
            }
            (Some(x), Some(y)) => {
                if x != y {
                    return x.cmp(y);
                }
                a = &a[1..];
                b = &b[1..];
            }
        }
    }
}

/// A cut sheet in 2D: its size and what is drawn on it, by layer.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Sheet {
    pub name: String,
    pub size: [f64; 2],
    pub figures: Vec<[String; 2]>,
    /// Polylines as (layer, closed, flat x, y list).
    pub paths: Vec<SheetPath>,
    pub parts: Vec<SheetPart>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct SheetPath {
    pub layer: String,
    pub closed: bool,
    pub points: Vec<f64>,
    /// The part it belongs to (index into the sheet's parts), if any.
    pub part: Option<u32>,
}

/// A part on a sheet: its id, where it is, its figures and where it is in the cut order.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SheetPart {
    pub id: String,
    /// Lower-left and upper-right corners of its outer contour, mm.
    pub bbox: [f64; 4],
    /// Where its outer contour's cut starts, mm.
    pub start: [f64; 2],
    /// Its place in the file's (and so the cut's) order, from 1.
    pub order: u32,
    pub figures: Vec<[String; 2]>,
}

/// Print layers: each a PNG of the lit region, with its islands.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Print {
    pub name: String,
    pub layer_mm: f64,
    /// Size of one image pixel on the plate, mm (a display pixel or a block of them).
    pub pixel_mm: f64,
    /// The region every image covers, in plate millimetres: x0, y0 (lower-left), x1, y1.
    pub region: [f64; 4],
    pub width: u32,
    pub height: u32,
    /// One PNG per layer as a data URL, or None for a layer with nothing lit.
    pub images: Vec<Option<String>>,
    pub islands: Vec<PrintIsland>,
    /// Islands found beyond those listed.
    pub more_islands: usize,
    pub figures: Vec<[String; 2]>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct PrintIsland {
    pub layer: usize,
    pub x_mm: f64,
    pub y_mm: f64,
    pub area_mm2: f64,
}

/// Packs f32 little-endian values into base64.
pub fn f32_blob(values: impl IntoIterator<Item = f32>) -> String {
    let bytes: Vec<u8> = values.into_iter().flat_map(f32::to_le_bytes).collect();
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// Packs u32 little-endian values into base64.
pub fn u32_blob(values: impl IntoIterator<Item = u32>) -> String {
    let bytes: Vec<u8> = values.into_iter().flat_map(u32::to_le_bytes).collect();
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A PNG as a data URL.
pub fn png_url(png: &[u8]) -> String {
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(png)
    )
}

/// An object while its layer is built: id, first element, element count, (column, value)
/// figures.
type Pending = (String, u32, u32, Vec<(usize, String)>);

/// Builds one layer: objects added one at a time, each with its own vertices.
pub struct LayerBuilder {
    name: String,
    kind: Kind,
    origin: DVec3,
    positions: Vec<f32>,
    indices: Vec<u32>,
    outline: Vec<u32>,
    columns: Vec<String>,
    objects: Vec<Pending>,
}

impl LayerBuilder {
    pub fn new(name: &str, kind: Kind, origin: DVec3) -> Self {
        LayerBuilder {
            name: name.into(),
            kind,
            origin,
            positions: Vec::new(),
            indices: Vec::new(),
            outline: Vec::new(),
            columns: Vec::new(),
            objects: Vec::new(),
        }
    }

    fn vertex(&mut self, p: DVec3) -> u32 {
        let n = (self.positions.len() / 3) as u32;
        let q = p - self.origin;
        self.positions.extend([q.x as f32, q.y as f32, q.z as f32]);
        n
    }

    fn elements(&self) -> usize {
        match self.kind {
            Kind::Faces => self.indices.len() / 3,
            Kind::Lines => self.indices.len() / 2,
            Kind::Points => self.positions.len() / 3,
        }
    }

    /// Adds an object of `triangles` over `points` (faces), with `outline` segments over the
    /// same points drawn dark.
    pub fn faces(
        &mut self,
        id: String,
        figures: Vec<[String; 2]>,
        points: &[DVec3],
        triangles: &[[u32; 3]],
        outline: &[[u32; 2]],
    ) {
        debug_assert_eq!(self.kind, Kind::Faces);
        let first = self.elements() as u32;
        let base: Vec<u32> = points.iter().map(|&p| self.vertex(p)).collect();
        for t in triangles {
            self.indices.extend(t.map(|i| base[i as usize]));
        }
        for s in outline {
            self.outline.extend(s.map(|i| base[i as usize]));
        }
        self.push(id, figures, first);
    }

    /// Adds an object of segments (consecutive point pairs).
    pub fn lines(&mut self, id: String, figures: Vec<[String; 2]>, segments: &[[DVec3; 2]]) {
        debug_assert_eq!(self.kind, Kind::Lines);
        let first = self.elements() as u32;
        for s in segments {
            let (a, b) = (self.vertex(s[0]), self.vertex(s[1]));
            self.indices.extend([a, b]);
        }
        self.push(id, figures, first);
    }

    /// Adds a point object.
    pub fn point(&mut self, id: String, figures: Vec<[String; 2]>, p: DVec3) {
        debug_assert_eq!(self.kind, Kind::Points);
        let first = self.elements() as u32;
        self.vertex(p);
        self.push(id, figures, first);
    }

    fn push(&mut self, id: String, figures: Vec<[String; 2]>, first: u32) {
        let figures = figures
            .into_iter()
            .map(|[name, value]| {
                let k = match self.columns.iter().position(|c| *c == name) {
                    Some(k) => k,
                    None => {
                        self.columns.push(name);
                        self.columns.len() - 1
                    }
                };
                (k, value)
            })
            .collect();
        let count = self.elements() as u32 - first;
        self.objects.push((id, first, count, figures));
    }

    /// How many elements so far (to bound a scene before it grows).
    pub fn len(&self) -> usize {
        self.elements()
    }

    pub fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }

    pub fn finish(self, colorings: Vec<Coloring>, visible: bool) -> Layer {
        let n = self.columns.len();
        let objects = self
            .objects
            .into_iter()
            .map(|(id, first, count, figures)| {
                let mut values = vec![String::new(); n];
                for (k, v) in figures {
                    values[k] = v;
                }
                Object {
                    id,
                    first,
                    count,
                    values,
                }
            })
            .collect();
        Layer {
            name: self.name,
            kind: self.kind,
            positions: f32_blob(self.positions),
            indices: u32_blob(self.indices),
            outline: u32_blob(self.outline),
            columns: self.columns,
            objects,
            colorings,
            visible,
        }
    }
}

/// A figure row: name and formatted value.
pub fn fig(name: &str, value: impl Into<String>) -> [String; 2] {
    [name.to_string(), value.into()]
}

/// The scene as JSON safe inside a `<script>` element: `<` written as `\u003c`, so no `</script>`
/// or `<!--` can end it early.
fn scene_json(scene: &Scene) -> String {
    serde_json::to_string(scene)
        .expect("scenes serialise")
        .replace('<', "\\u003c")
}

/// The viewer as a block to put inside a page's `<body>`: its style, a container of `height`
/// (CSS), the scene, three.js and the viewer's script.
pub fn embed(scene: &Scene, height: &str) -> String {
    // three.js only where there is something to draw in 3D (not on sheet and print pages).
    let three = if scene.layers.is_empty() {
        String::new()
    } else {
        format!(
            "<script type=\"text/plain\" id=\"three-core\">{THREE_CORE}</script>\n\
             <script type=\"text/plain\" id=\"three-module\">{THREE_MODULE}</script>\n\
             <script type=\"text/plain\" id=\"three-orbit\">{ORBIT_CONTROLS}</script>\n\
             <!-- three.js {THREE_VERSION}, vendored unchanged from the npm registry:\n{}-->\n",
            THREE_LICENSE.replace("--", "- -"),
        )
    };
    format!(
        "<style>{VIEWER_CSS}</style>\n\
         <div id=\"lamina-viewer\" style=\"height:{}\"></div>\n\
         <script type=\"application/json\" id=\"lamina-data\">{}</script>\n\
         {three}<script type=\"module\">{VIEWER_JS}</script>\n",
        html(height),
        scene_json(scene),
    )
}

/// A standalone page: the viewer filling the window.
pub fn page(scene: &Scene) -> String {
    format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width,initial-scale=1\">\n\
         <title>{}</title>\n\
         <style>html,body{{margin:0;height:100%;font:14px/1.4 system-ui,sans-serif;color:#222}}</style>\n\
         </head><body>\n{}</body></html>\n",
        html(&scene.title),
        embed(scene, "100vh")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blobs_are_little_endian_base64() {
        assert_eq!(u32_blob([1u32]), "AQAAAA==");
        assert_eq!(f32_blob([1.0f32]), "AACAPw==");
    }

    #[test]
    fn scene_text_cannot_close_its_script_element() {
        let scene = Scene {
            title: "</script><script>alert(1)</script>".into(),
            notes: vec!["<!-- x".into()],
            ..Scene::default()
        };
        let page = page(&scene);
        let data = page
            .split("id=\"lamina-data\">")
            .nth(1)
            .and_then(|s| s.split("</script>").next())
            .expect("a data element");
        assert!(!data.contains('<'), "{data}");
        let back: serde_json::Value =
            serde_json::from_str(data).expect("the data element holds JSON");
        assert_eq!(back["title"], "</script><script>alert(1)</script>");
        assert!(page.contains("&lt;/script&gt;"), "the title is escaped");
    }

    #[test]
    fn objects_index_their_own_elements() {
        let mut b = LayerBuilder::new("t", Kind::Faces, DVec3::new(10.0, 0.0, 0.0));
        let sq = [
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(11.0, 0.0, 0.0),
            DVec3::new(11.0, 1.0, 0.0),
            DVec3::new(10.0, 1.0, 0.0),
        ];
        b.faces(
            "a".into(),
            vec![fig("x", "1"), fig("y", "2")],
            &sq,
            &[[0, 1, 2], [0, 2, 3]],
            &[[0, 1]],
        );
        b.faces("b".into(), vec![fig("y", "3")], &sq[..3], &[[0, 1, 2]], &[]);
        let l = b.finish(vec![], true);
        assert_eq!((l.objects[0].first, l.objects[0].count), (0, 2));
        assert_eq!((l.objects[1].first, l.objects[1].count), (2, 1));
        let idx = base64::engine::general_purpose::STANDARD
            .decode(&l.indices)
            .expect("base64");
        let idx: Vec<u32> = idx
            .chunks(4)
            .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect();
        assert_eq!(idx, vec![0, 1, 2, 0, 2, 3, 4, 5, 6]);
        assert_eq!(l.columns, ["x", "y"]);
        assert_eq!(l.objects[1].values, ["", "3"]);
    }

    #[test]
    fn categories_are_listed_in_natural_order() {
        let of: Vec<String> = [
            "group 10", "group 2", "group 1", "group 2", "core", "group 02",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let c = Coloring::categories("group", "", &of);
        assert_eq!(
            c.labels,
            ["core", "group 1", "group 2", "group 02", "group 10"]
        );
        assert_eq!(
            c.values,
            [
                Some(4.0),
                Some(2.0),
                Some(1.0),
                Some(2.0),
                Some(0.0),
                Some(3.0)
            ]
        );
    }

    #[test]
    fn classes_keep_their_order_and_colours_whatever_the_objects() {
        let c = Coloring::classes("access", "", &PASS_FAIL, &[Some(1), None, Some(7)]);
        assert_eq!(c.labels, ["within", "above"]);
        assert_eq!(c.colors, ["#2ca02c", "#d62728"]);
        assert_eq!(c.values, [Some(1.0), None, None]);
    }
}

#[cfg(test)]
mod asset_tests {
    use super::*;

    #[test]
    fn no_embedded_script_can_end_its_element_early() {
        for (name, text) in [
            ("three.core", THREE_CORE),
            ("three.module", THREE_MODULE),
            ("orbit", ORBIT_CONTROLS),
            ("viewer", VIEWER_JS),
        ] {
            let lower = text.to_ascii_lowercase();
            assert!(!lower.contains("</script"), "{name}");
            assert!(!lower.contains("<!--"), "{name}");
        }
        // The import specifiers the page rewrites are where it expects them.
        assert!(THREE_MODULE.contains("\"./three.core.min.js\""));
        assert!(ORBIT_CONTROLS.contains("from 'three'"));
        assert!(THREE_LICENSE.contains("MIT"));
    }
}
