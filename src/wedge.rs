//! Wedges, as Houdini's Wedge TOP makes them: render a graph once per combination of parameter
//! values and compare the results side by side.
//!
//! `--wedge wind.seed=1,2,3` is one axis; several `--wedge`s multiply (2 × 3 = 6 variants);
//! every `--wedge-zip` joins one axis whose parameters vary together (equal counts). A variant
//! is named from its values (`wind.noise_c-0.02_wind.seed-1`). Text parameters of the graph may
//! use `{wedge}` (the name) and `{wedge.PARAM}` (`{wedge.seed}` or `{wedge.wind.seed}`: the
//! value); a graph that uses neither writes each variant into `OUT/<name>/`, so variants never
//! overwrite each other.

use std::path::Path;

use pyrograph_core::{GraphDoc, Image, ParamValue};

/// One parameter of an axis and its values as typed (RON).
#[derive(Clone, Debug, PartialEq)]
pub struct WedgeParam {
    /// `node.param`.
    pub target: String,
    /// The values, in order.
    pub values: Vec<String>,
}

/// Most variants one wedge may have (all its axes' values multiplied).
pub const MAX_VARIANTS: usize = 10_000;

/// The axes of a wedge: parameters on one axis vary together; axes multiply.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Wedges {
    /// The axes, outermost first.
    pub axes: Vec<Vec<WedgeParam>>,
}

/// One combination.
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    /// Position in the product, 0-based.
    pub index: usize,
    /// `(node.param, value)` for every wedged parameter.
    pub sets: Vec<(String, String)>,
    /// File-name-safe name built from the values.
    pub name: String,
}

/// Splits `a,b,(1, 2),"x,y"` at the commas outside brackets and quotes.
fn split_values(text: &str) -> Vec<String> {
    let (mut out, mut cur, mut depth, mut quoted) = (Vec::new(), String::new(), 0i32, false);
    for c in text.chars() {
        match c {
            '"' => quoted = !quoted,
            '(' | '[' if !quoted => depth += 1,
            ')' | ']' if !quoted => depth -= 1,
            ',' if !quoted && depth == 0 => {
                out.push(cur.trim().to_string());
                cur.clear();
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    out.push(cur.trim().to_string());
    out
}

fn parse_param(arg: &str) -> Result<WedgeParam, String> {
    let (target, values) = arg.split_once('=').ok_or_else(|| format!("--wedge {arg}: expected node.param=v1,v2,…"))?;
    if pyrograph_core::document::split_endpoint(target).is_none() {
        return Err(format!("--wedge {arg}: '{target}' is not of the form node.param"));
    }
    let values = split_values(values);
    if values.iter().any(String::is_empty) {
        return Err(format!("--wedge {arg}: an empty value; list values like 0.5,1,2"));
    }
    Ok(WedgeParam { target: target.trim().to_string(), values })
}

impl Wedges {
    /// Axes from `--wedge` arguments (one axis each) and `--wedge-zip` arguments (one shared axis).
    pub fn parse(wedge: &[String], zip: &[String]) -> Result<Wedges, String> {
        let mut axes: Vec<Vec<WedgeParam>> = wedge.iter().map(|a| parse_param(a).map(|p| vec![p])).collect::<Result<_, _>>()?;
        if !zip.is_empty() {
            let params: Vec<WedgeParam> = zip.iter().map(|a| parse_param(a)).collect::<Result<_, _>>()?;
            let n = params[0].values.len();
            if let Some(p) = params.iter().find(|p| p.values.len() != n) {
                return Err(format!(
                    "--wedge-zip {}: {} values, but {} has {n}; zipped parameters vary together, so they need as many values",
                    p.target,
                    p.values.len(),
                    params[0].target
                ));
            }
            axes.push(params);
        }
        let mut seen = std::collections::HashSet::new();
        if let Some(p) = axes.iter().flatten().find(|p| !seen.insert(p.target.clone())) {
            return Err(format!("--wedge: {} is wedged twice", p.target));
        }
        // Axes multiply: a few long ones would be more variants than any farm renders (or than a
        // machine word counts), listed before the first is cooked.
        let counts: Vec<usize> = axes.iter().map(|a| a[0].values.len()).collect();
        let total = counts.iter().try_fold(1usize, |t, n| t.checked_mul(*n).filter(|t| *t <= MAX_VARIANTS));
        if total.is_none() {
            let shape: Vec<String> = counts.iter().map(usize::to_string).collect();
            return Err(format!(
                "--wedge: {} values multiply to more than the {MAX_VARIANTS} variants one command renders; split the \
                 wedge into several commands, or vary fewer parameters together",
                shape.join(" × ")
            ));
        }
        Ok(Wedges { axes })
    }

    /// Whether there is anything to wedge.
    pub fn is_empty(&self) -> bool {
        self.axes.is_empty()
    }

    /// The length of each axis.
    pub fn shape(&self) -> Vec<usize> {
        self.axes.iter().map(|a| a[0].values.len()).collect()
    }

    /// Every combination, the last axis varying fastest; none without axes.
    pub fn variants(&self) -> Vec<Variant> {
        if self.axes.is_empty() {
            return Vec::new();
        }
        let shape = self.shape();
        let total: usize = shape.iter().product();
        (0..total)
            .map(|index| {
                let mut rest = index;
                let mut picks = vec![0; shape.len()];
                for (k, n) in shape.iter().enumerate().rev() {
                    picks[k] = rest % n;
                    rest /= n;
                }
                let sets: Vec<(String, String)> = self
                    .axes
                    .iter()
                    .zip(&picks)
                    .flat_map(|(axis, &i)| axis.iter().map(move |p| (p.target.clone(), p.values[i].clone())))
                    .collect();
                let name = sets.iter().map(|(t, v)| format!("{t}-{}", safe(v))).collect::<Vec<_>>().join("_");
                Variant { index, sets, name }
            })
            .collect()
    }
}

/// `v` with every character outside `A-Za-z0-9.-` replaced, for file names.
fn safe(v: &str) -> String {
    let mut s = String::new();
    for c in v.chars() {
        let c = if c.is_ascii_alphanumeric() || c == '.' || c == '-' { c } else { '_' };
        if !(c == '_' && s.ends_with('_')) {
            s.push(c);
        }
    }
    s.trim_matches('_').to_string()
}

impl Variant {
    /// The `{wedge…}` tokens and their text.
    fn tokens(&self) -> Vec<(String, String)> {
        let mut t = vec![("{wedge}".to_string(), self.name.clone())];
        for (target, value) in &self.sets {
            let shown = value.trim_matches('"').to_string();
            t.push((format!("{{wedge.{target}}}"), shown.clone()));
            if let Some((_, param)) = target.rsplit_once('.') {
                t.push((format!("{{wedge.{param}}}"), shown));
            }
        }
        t
    }

    /// Sets the variant's values in `doc` and fills the `{wedge…}` tokens of its text
    /// parameters; returns whether any token was used (then outputs need no folder of their own).
    pub fn apply(&self, doc: &mut GraphDoc) -> Result<bool, String> {
        for (target, value) in &self.sets {
            let (node, param) = pyrograph_core::document::split_endpoint(target).unwrap_or_default();
            doc.set_param(node, param, ParamValue::parse_cli(value)).map_err(|e| format!("--wedge {target}: {e}"))?;
        }
        let tokens = self.tokens();
        let mut used = false;
        for (_, nd) in doc.nodes.0.iter_mut() {
            for v in nd.params.values_mut() {
                if let ParamValue::String(text) = v
                    && text.contains("{wedge")
                {
                    for (k, val) in &tokens {
                        *text = text.replace(k.as_str(), val);
                    }
                    used = true;
                }
            }
        }
        Ok(used)
    }

    /// One label line per wedged parameter: `seed = 2`.
    pub fn label(&self) -> Vec<String> {
        self.sets.iter().map(|(t, v)| format!("{} = {}", t.rsplit_once('.').map_or(t.as_str(), |(_, p)| p), v)).collect()
    }
}

/// A labelled contact sheet: one cell per variant (its image scaled to `cell_width`), laid out
/// with the last axis across; the labels are drawn under each picture in Hack (egui's
/// monospace font, MIT/Bitstream Vera licence), rasterized by ab_glyph.
pub fn sheet(cells: &[(Image, Vec<String>)], columns: usize, cell_width: u32) -> Result<Image, String> {
    use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
    let font = FontRef::try_from_slice(epaint_default_fonts::HACK_REGULAR).map_err(|e| e.to_string())?;
    let scale = PxScale::from(15.0);
    let scaled = font.as_scaled(scale);
    let line = scaled.height().ceil() as u32 + 2;
    let lines = cells.iter().map(|c| c.1.len()).max().unwrap_or(0) as u32;
    let pics: Vec<Image> = cells
        .iter()
        .map(|(img, _)| {
            pyrograph_frontend::imaging::resize::resize(
                &img.to_rgba(),
                cell_width,
                0,
                pyrograph_frontend::imaging::resize::ResizeFilter::Bilinear.filter_type(),
            )
            .map_err(|e| e.to_string())
        })
        .collect::<Result<_, _>>()?;
    let cell_h = pics.iter().map(Image::height).max().unwrap_or(1);
    let (pad, columns) = (8u32, columns.max(1) as u32);
    let rows = (cells.len() as u32).div_ceil(columns);
    let (cw, ch) = (cell_width + pad, cell_h + lines * line + pad * 2);
    let (w, h) = (columns * cw + pad, rows * ch + pad);
    let mut out = Image::new(w, h, pyrograph_core::Channels::Rgba);
    let data = out.data_mut();
    for px in data.chunks_exact_mut(4) {
        px.copy_from_slice(&[0.06, 0.06, 0.07, 1.0]);
    }
    for (i, (pic, (_, label))) in pics.iter().zip(cells).enumerate() {
        let (x0, y0) = ((i as u32 % columns) * cw + pad, (i as u32 / columns) * ch + pad);
        for y in 0..pic.height() {
            let src = &pic.data()[(y * pic.width() * 4) as usize..((y + 1) * pic.width() * 4) as usize];
            let at = (((y0 + y) * w + x0) * 4) as usize;
            data[at..at + src.len()].copy_from_slice(src);
        }
        for (k, text) in label.iter().enumerate() {
            let mut caret = x0 as f32;
            let baseline = (y0 + cell_h + pad / 2 + k as u32 * line) as f32 + scaled.ascent();
            for c in text.chars() {
                let id = font.glyph_id(c);
                let glyph = id.with_scale_and_position(scale, ab_glyph::point(caret, baseline));
                caret += scaled.h_advance(id);
                if let Some(outline) = font.outline_glyph(glyph) {
                    let b = outline.px_bounds();
                    outline.draw(|gx, gy, cov| {
                        let (x, y) = (b.min.x as i64 + gx as i64, b.min.y as i64 + gy as i64);
                        if (0..w as i64).contains(&x) && (0..h as i64).contains(&y) {
                            let at = ((y as u32 * w + x as u32) * 4) as usize;
                            for ch in &mut data[at..at + 3] {
                                *ch += (0.92 - *ch) * cov;
                            }
                        }
                    });
                }
            }
        }
    }
    Ok(out)
}

/// The picture of a variant for its sheet cell: the middle image of the files it wrote.
pub fn cell_image(files: &[std::path::PathBuf]) -> Option<&Path> {
    let mut images: Vec<&Path> = files
        .iter()
        .map(|p| p.as_path())
        .filter(|p| {
            p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("exr"))
        })
        .collect();
    images.sort();
    images.get(images.len() / 2).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(wedge: &[&str], zip: &[&str]) -> Result<Wedges, String> {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        Wedges::parse(&s(wedge), &s(zip))
    }

    #[test]
    fn a_wedge_of_too_many_variants_is_refused_before_any_is_listed() {
        let hundred: Vec<String> = (0..100).map(|i| i.to_string()).collect();
        let axis = |name: &str| format!("{name}.x={}", hundred.join(","));
        let axes: Vec<String> = ["a", "b", "c", "d", "e", "f", "g", "h", "i", "j"].iter().map(|n| axis(n)).collect();
        // 100^10 overflows a machine word; 100 × 100 × 100 is just over the limit.
        for n in [10, 3] {
            let e = Wedges::parse(&axes[..n], &[]).unwrap_err();
            assert!(e.contains("100 × 100 × 100") && e.contains("10000 variants"), "{e}");
        }
        assert_eq!(Wedges::parse(&axes[..2], &[]).unwrap().variants().len(), 10_000);
    }

    #[test]
    fn axes_multiply_and_zips_vary_together() {
        let wedges = w(&["a.x=1,2", "b.y=(1, 0, 0),(0, 1, 0),\"p,q\""], &["c.s=0.5,1", "d.t=3,4"]).unwrap();
        assert_eq!(wedges.shape(), [2, 3, 2]);
        let v = wedges.variants();
        assert_eq!(v.len(), 12);
        assert_eq!(
            v[0].sets,
            [("a.x", "1"), ("b.y", "(1, 0, 0)"), ("c.s", "0.5"), ("d.t", "3")].map(|(a, b)| (a.into(), b.into()))
        );
        assert_eq!(v[1].sets[2..], [("c.s".into(), "1".into()), ("d.t".into(), "4".into())], "zipped values move together");
        assert_eq!(v[11].name, "a.x-2_b.y-p_q_c.s-1_d.t-4");
        let names: std::collections::HashSet<_> = v.iter().map(|x| x.name.clone()).collect();
        assert_eq!(names.len(), 12, "every variant has its own name");
    }

    #[test]
    fn no_axes_no_variants() {
        assert!(w(&[], &[]).unwrap().variants().is_empty());
    }

    #[test]
    fn bad_wedges_say_why() {
        assert!(w(&["a.x"], &[]).unwrap_err().contains("expected node.param=v1,v2"));
        assert!(w(&["ax=1"], &[]).unwrap_err().contains("not of the form node.param"));
        assert!(w(&["a.x=1,,2"], &[]).unwrap_err().contains("empty value"));
        assert!(w(&[], &["a.x=1,2", "b.y=1"]).unwrap_err().contains("as many values"));
        assert!(w(&["a.x=1", "a.x=2"], &[]).unwrap_err().contains("wedged twice"));
    }

    #[test]
    fn tokens_fill_text_parameters() {
        let mut doc = GraphDoc::from_ron(
            r#"(version: 1, nodes: {"wind": (type: "particles.wind_field"),
                "write": (type: "imaging.write_sequence", params: {"pattern": "{wedge}/s{wedge.seed}_####.png"})})"#,
        )
        .unwrap();
        let v = &w(&["wind.seed=4,5"], &[]).unwrap().variants()[1];
        assert!(v.apply(&mut doc).unwrap());
        assert_eq!(doc.node("write").unwrap().params["pattern"], ParamValue::String("wind.seed-5/s5_####.png".into()));
        assert_eq!(doc.node("wind").unwrap().params["seed"], ParamValue::Int(5));
        assert_eq!(v.label(), ["seed = 5"]);
    }
}
