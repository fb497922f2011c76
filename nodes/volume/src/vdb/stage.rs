//! The USD stage beside a VDB sequence: a `Volume` prim whose fields are `OpenVDBAsset` prims with
//! their `filePath` sampled at every frame (UsdVol's schema), so Solaris, Omniverse or usdview
//! reference the simulation as a volume.

use std::path::Path;

use pyrograph_usd::{asset, attribute, define, relationship, sample};

/// One field of the stage: its grid name and whether it holds vectors.
pub struct StageField {
    /// Grid name (`density`, `vel`).
    pub name: String,
    /// A vec3 grid.
    pub vector: bool,
}

/// What the stage holds.
pub struct StageSpec<'a> {
    /// The Volume prim's name under /World.
    pub name: &'a str,
    /// Its fields.
    pub fields: &'a [StageField],
    /// Every frame's VDB file, relative to the stage (or absolute), by frame.
    pub files: &'a [String],
    /// Frames per second.
    pub fps: f64,
}

/// The stage as `.usda` text.
pub fn stage_text(spec: &StageSpec) -> anyhow::Result<Vec<u8>> {
    let stage = pyrograph_usd::new_stage(spec.files.len(), spec.fps)?;
    let volume = format!("/World/{}", spec.name);
    // No `extent`: a farm writes the stage with the chunk holding frame 0, before the other
    // chunks' volumes exist, and a stage must not differ with how the frames were chunked. The
    // readers (Solaris, usdview, Omniverse) take a volume's bounds from its VDB files.
    define(&stage, &volume, "Volume")?;
    for f in spec.fields {
        let prim = format!("{volume}/{}", f.name);
        define(&stage, &prim, "OpenVDBAsset")?;
        pyrograph_usd::uniform_token(&stage, &prim, "fieldName", &f.name)?;
        pyrograph_usd::uniform_token(&stage, &prim, "fieldDataType", if f.vector { "float3" } else { "float" })?;
        if f.vector {
            pyrograph_usd::uniform_token(&stage, &prim, "vectorDataRoleHint", "Vector")?;
        }
        let path = attribute(&stage, &prim, "filePath", "asset", false)?;
        for (t, file) in spec.files.iter().enumerate() {
            sample(&path, t, asset(file))?;
        }
        relationship(&stage, &volume, &format!("field:{}", f.name), &[&prim])?;
    }
    pyrograph_usd::finish(&stage)
}

/// `file` as the stage at `stage` should name it: relative to the stage's folder when it is
/// inside it (`./vdb/smoke_0001.vdb`), absolute otherwise.
pub fn asset_path(file: &Path, stage: &Path) -> String {
    let dir = stage.parent().unwrap_or(Path::new(""));
    match file.strip_prefix(dir) {
        Ok(rel) => format!("./{}", rel.to_string_lossy()),
        Err(_) => file.to_string_lossy().into_owned(),
    }
}
