//! Colours: the viewer names them in sRGB; the shaders blend in linear light.

/// sRGB → linear for one channel.
fn linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// An sRGB colour as a linear, opaque RGBA one (what the shaders take).
pub(crate) fn linear_rgba(c: [f32; 3]) -> [f32; 4] {
    [linear(c[0]), linear(c[1]), linear(c[2]), 1.0]
}
