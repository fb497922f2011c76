//! Engine conventions for flipbooks: how each engine's flipbook material reads a motion sheet
//! (units, axes, sign), the number the artist pastes into it, and the side-car lines that say so.
//!
//! The sheet's cell order is the same for all of them (frame 0 top-left, left to right, then top
//! to bottom in the image file): Unity's `GetSubUV` counts rows from the top of a bottom-left-origin
//! texture, Unreal's SubUV and the SideFX Labs shader from the top of a top-left-origin one.

pyrograph_core::choice! {
    /// Which engine's flipbook material a motion sheet is encoded for.
    pub enum Convention {
        /// pyrograph's own: R = 0.5 + dx / (2·range), G = 0.5 + dy / (2·range), frame pixels, y down.
        Generic = "generic",
        /// Unity VFX Graph, UV mode Flipbook Motion Blend: (rg·2 − 1) · Motion Vector Scale in cell UVs, y up.
        Unity = "unity",
        /// Unreal frame-blending material: (rg − 0.5) · 2 · strength in sheet UVs, y down.
        Unreal = "unreal",
        /// SideFX Labs motion-vector shader: (rg − 0.5) · 2 · Distortion in cell UVs, G flipped, sampled against the motion.
        HoudiniLabs = "houdini-labs",
    }
}

/// Sheet and frame geometry a motion code depends on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SheetGeometry {
    /// Source frame size (where the flow is measured), in pixels.
    pub source: (u32, u32),
    /// Frame size inside a cell, in sheet pixels.
    pub frame: (u32, u32),
    /// Cell size, in sheet pixels.
    pub cell: (u32, u32),
    /// Sheet size, in pixels.
    pub sheet: (u32, u32),
}

/// How a motion of (dx, dy) source pixels (x right, y down) becomes the sheet's R and G:
/// `R = 0.5 + dx / div.0`, `G = 0.5 + dy / div.1`, clamped to 0..1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionCode {
    /// Divisors of dx and dy (their signs carry the engine's axis directions).
    pub div: (f32, f32),
    /// The number the engine's material takes (Motion Vector Scale, strength, Distortion; for
    /// `generic`, the range in source pixels).
    pub scale: f32,
}

impl MotionCode {
    /// R and G of a motion in source pixels.
    pub fn encode(&self, dx: f32, dy: f32) -> (f32, f32) {
        if !(dx.is_finite() && dy.is_finite()) {
            // Flow through NaN or infinite pixels (an EXR frame can hold them) means nothing: no
            // motion, rather than a NaN the engine would sample the texture at.
            return (0.5, 0.5);
        }
        ((0.5 + dx / self.div.0).clamp(0.0, 1.0), (0.5 + dy / self.div.1).clamp(0.0, 1.0))
    }

    /// The motion in source pixels that R and G stand for (the inverse of `encode` inside its range).
    pub fn decode(&self, r: f32, g: f32) -> (f32, f32) {
        ((r - 0.5) * self.div.0, (g - 0.5) * self.div.1)
    }
}

impl Convention {
    /// The engine's unit length in sheet pixels along x and y (a cell for UVs per cell, the sheet
    /// for UVs of the whole texture) and the signs of its axes against pyrograph's (x right, y down,
    /// the motion from each frame to the next).
    fn unit_and_signs(self, g: &SheetGeometry) -> ((f32, f32), (f32, f32)) {
        let cell = (g.cell.0 as f32, g.cell.1 as f32);
        match self {
            Convention::Generic => ((1.0, 1.0), (1.0, 1.0)),
            // Unity: VFXCommon.hlsl adds (rg·2−1)·motionVectorScale·invFlipBookSize to the sheet UV,
            // whose v points up; a cell's UV extent is invFlipBookSize.
            Convention::Unity => (cell, (1.0, -1.0)),
            // Unreal: UVs have v down; the strength multiplies the decoded vector in sheet UVs.
            Convention::Unreal => ((g.sheet.0 as f32, g.sheet.1 as f32), (1.0, 1.0)),
            // SideFX Labs: G is flipped (1 − g) and the vector is added to frame t's UV (subtracted
            // from frame t+1's), so it points against the motion on both axes of the image.
            Convention::HoudiniLabs => (cell, (-1.0, -1.0)),
        }
    }

    /// The motion code for a motion range of `range` source pixels (what maps to 0 or 1).
    pub fn motion_code(self, range: f32, g: &SheetGeometry) -> MotionCode {
        if self == Convention::Generic {
            return MotionCode { div: (2.0 * range, 2.0 * range), scale: range };
        }
        let ((ux, uy), (sx, sy)) = self.unit_and_signs(g);
        // Sheet pixels per source pixel (the frames may have been resized into their cells).
        let fx = g.frame.0 as f32 / g.source.0.max(1) as f32;
        let fy = g.frame.1 as f32 / g.source.1.max(1) as f32;
        // One scale for both axes (the engines take one number): the larger axis fills 0..1.
        let scale = range * (fx / ux).max(fy / uy);
        MotionCode { div: (sx * 2.0 * scale * ux / fx, sy * 2.0 * scale * uy / fy), scale }
    }

    /// Whether each cell holds the velocity at its frame (the mean of the motion from the previous
    /// frame and to the next) rather than the motion to the next frame: Unity and Unreal move frame
    /// t+1 by its own cell's vector, so that vector must also say how frame t+1 arrived; the Labs
    /// shader moves both frames by frame t's vector, which is then best the motion from t to t+1.
    pub fn central_vectors(self) -> bool {
        matches!(self, Convention::Unity | Convention::Unreal)
    }

    /// Whether the automatic motion range takes the largest vector (16-bit sheets have the
    /// precision) rather than the 99th percentile (8-bit sheets need the steps).
    pub fn wants_largest_range(self) -> bool {
        self != Convention::Generic
    }

    /// The engine-specific side-car lines (JSON members, each ending in ",\n"), empty for `generic`.
    pub fn sidecar(self, code: &MotionCode, rows: usize, cols: usize, motion_bits: u32) -> String {
        let (engine, setting, decode, settings) = match self {
            Convention::Generic => return String::new(),
            Convention::Unity => (
                "Unity VFX Graph",
                "Motion Vector Scale",
                "uv_t' = uv_t - (rg * 2 - 1) * scale / flipBookSize * blend; uv_t+1' = uv_t+1 + (rg * 2 - 1) * scale / \
                 flipBookSize * (1 - blend); v up",
                format!(
                    "UV Mode: Flipbook Motion Blend; Flip Book Size: ({cols}, {rows}); Motion Vector Scale: {}; \
                     motion texture: sRGB off, Compression None, {motion_bits}-bit",
                    code.scale
                ),
            ),
            Convention::Unreal => (
                "Unreal Engine",
                "Motion Vector Strength",
                "uv_t' = uv_t - (rg - 0.5) * 2 * strength * phase; uv_t+1' = uv_t+1 + (rg - 0.5) * 2 * strength * (1 - phase); \
                 sheet UVs, v down",
                format!(
                    "SubUV: {cols} x {rows}; strength: {}; motion texture: sRGB off, Compression HDR (RGBA16F) or \
                     uncompressed, {motion_bits}-bit, neutral 0.5",
                    code.scale
                ),
            ),
            Convention::HoudiniLabs => (
                "SideFX Labs (sidefx/MotionVector shader)",
                "Distortion",
                "g = 1 - g; uv_t' = uv_t + (rg - 0.5) * 2 / (cols, rows) * distortion * blend; uv_t+1' = uv_t+1 - (rg - 0.5) * 2 \
                 / (cols, rows) * distortion * (1 - blend)",
                format!(
                    "Rows: {rows}; Columns: {cols}; Distortion: {}; motion texture: sRGB off, uncompressed, {motion_bits}-bit",
                    code.scale
                ),
            ),
        };
        let quote = |s: &str| format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""));
        format!(
            "  \"convention\": {},\n  \"engine\": {},\n  \"engine_setting\": {},\n  \"engine_value\": {},\n  \
             \"engine_decode\": {},\n  \"engine_settings\": {},\n  \"motion_bits\": {motion_bits},\n",
            quote(self.name()),
            quote(engine),
            quote(setting),
            code.scale,
            quote(decode),
            quote(&settings),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry() -> SheetGeometry {
        // 100×50 source frames resized to 64×32 in 72×40 cells on a 4×2 sheet (288×80).
        SheetGeometry { source: (100, 50), frame: (64, 32), cell: (72, 40), sheet: (288, 80) }
    }

    #[test]
    fn generic_is_the_old_encoding() {
        let code = Convention::Generic.motion_code(4.0, &geometry());
        assert_eq!(code.encode(2.0, -4.0), (0.75, 0.0));
        assert_eq!(code.scale, 4.0);
    }

    #[test]
    fn every_convention_decodes_what_it_encodes_and_fills_the_range_on_one_axis() {
        let g = geometry();
        for c in [Convention::Unity, Convention::Unreal, Convention::HoudiniLabs] {
            let code = c.motion_code(10.0, &g);
            let (r, gg) = code.encode(3.0, -7.0);
            let (dx, dy) = code.decode(r, gg);
            assert!((dx - 3.0).abs() < 1e-4 && (dy + 7.0).abs() < 1e-4, "{c:?}: ({dx}, {dy})");
            // 10 px along the axis that is larger in engine units reaches 0 or 1 exactly.
            let (a, b) = (code.encode(10.0, 0.0).0, code.encode(0.0, 10.0).1);
            assert!([a, b].iter().any(|v| *v < 1e-6 || *v > 1.0 - 1e-6), "{c:?}: {a} {b}");
        }
    }

    #[test]
    fn unity_points_v_up_and_labs_against_the_motion() {
        let g = geometry();
        // A motion right and down: Unity R up, G down; Labs both down; Unreal both up.
        let (ur, ug) = Convention::Unity.motion_code(10.0, &g).encode(2.0, 2.0);
        assert!(ur > 0.5 && ug < 0.5);
        let (lr, lg) = Convention::HoudiniLabs.motion_code(10.0, &g).encode(2.0, 2.0);
        assert!(lr < 0.5 && lg < 0.5);
        let (er, eg) = Convention::Unreal.motion_code(10.0, &g).encode(2.0, 2.0);
        assert!(er > 0.5 && eg > 0.5);
        // Unity's scale is in cell UVs: 10 source px are 6.4 sheet px along x, 6.4 / 72 of a cell;
        // along y 6.4 px of a 40 px cell is larger, so the scale is 6.4 / 40.
        assert!((Convention::Unity.motion_code(10.0, &g).scale - 6.4 / 40.0).abs() < 1e-6);
    }
}
