//! A view read back: linear RGB with a sample count per pixel, and its 8-bit sRGB and f32 forms.

use lodestone_core::material::colormap::linear_to_srgb;

/// A linear-RGB image; `pixels[i][3]` is the sample count (1 for the analytic views).
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Row-major RGB + weight.
    pub pixels: Vec<[f32; 4]>,
}

impl LinearImage {
    /// Linear RGB of pixel (x, y), divided by its weight.
    pub fn rgb(&self, x: u32, y: u32) -> [f32; 3] {
        let p = self.pixels[(y * self.width + x) as usize];
        let w = if p[3] > 0.0 { p[3] } else { 1.0 };
        [p[0] / w, p[1] / w, p[2] / w]
    }

    /// 8-bit sRGB, opaque.
    pub fn to_srgb8(&self) -> image::RgbaImage {
        image::RgbaImage::from_fn(self.width, self.height, |x, y| {
            let c = self
                .rgb(x, y)
                .map(|v| (linear_to_srgb(f64::from(v)) * 255.0).round() as u8);
            image::Rgba([c[0], c[1], c[2], 255])
        })
    }

    /// Linear RGBA f32 (alpha 1), for EXR.
    pub fn to_linear_f32(&self) -> image::Rgba32FImage {
        image::Rgba32FImage::from_fn(self.width, self.height, |x, y| {
            let c = self.rgb(x, y);
            image::Rgba([c[0], c[1], c[2], 1.0])
        })
    }
}
