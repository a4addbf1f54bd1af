//! PNG and GIF encoding of rendered pictures, and the contact sheet layout.

use rayon::prelude::*;

use crate::raster::{Framebuffer, Rgba};
use crate::{palette, RenderError};

/// Encodes `fb` as an 8-bit RGBA PNG (default compression, no ancillary chunks, so the
/// bytes depend only on the pixels).
///
/// # Errors
/// [`RenderError::Png`] if the encoder fails (e.g. a zero-sized picture).
pub fn encode_png(fb: &Framebuffer) -> Result<Vec<u8>, RenderError> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, fb.width(), fb.height());
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header()?;
    let bytes: Vec<u8> = fb.pixels().iter().flatten().copied().collect();
    writer.write_image_data(&bytes)?;
    writer.finish()?;
    Ok(out)
}

/// Encodes `frames` (all the same size) as a looping animated PNG (APNG, RGBA8), each
/// shown `delay_ms` milliseconds (the `fcTL` delay as `delay_ms / 1000` s; APNG spec
/// "fcTL"). The first frame is also the still image non-animating viewers show.
///
/// # Errors
/// [`RenderError::EmptyAnimation`] without frames, [`RenderError::FrameSize`] if the
/// frames differ in size, [`RenderError::Png`] if the encoder fails.
pub fn encode_apng(frames: &[Framebuffer], delay_ms: u16) -> Result<Vec<u8>, RenderError> {
    let first = frames.first().ok_or(RenderError::EmptyAnimation)?;
    let (w, h) = (first.width(), first.height());
    let count = u32::try_from(frames.len()).map_err(|_| RenderError::EmptyAnimation)?;
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_animated(count, 0)?;
    enc.set_frame_delay(delay_ms, 1000)?;
    let mut writer = enc.write_header()?;
    for fb in frames {
        if fb.width() != w || fb.height() != h {
            return Err(RenderError::FrameSize {
                width: fb.width(),
                height: fb.height(),
            });
        }
        let bytes: Vec<u8> = fb.pixels().iter().flatten().copied().collect();
        writer.write_image_data(&bytes)?;
    }
    writer.finish()?;
    Ok(out)
}

/// The APNG frame delay in milliseconds for `fps` frames per second: rounded, 1 to 65535.
pub fn apng_delay_ms(fps: f32) -> u16 {
    let ms = (1000.0 / fps).round();
    if ms.is_finite() {
        ms.clamp(1.0, 65535.0) as u16
    } else {
        1
    }
}

/// The GIF frame delay in hundredths of a second for `fps` frames per second: rounded, at
/// least 2 (browsers slow delays below 2 down to 10; see the GIF89a Graphic Control
/// Extension's "Delay Time").
pub fn gif_delay_cs(fps: f32) -> u16 {
    let cs = (100.0 / fps).round();
    if cs.is_finite() {
        cs.clamp(2.0, 65535.0) as u16
    } else {
        2
    }
}

/// Encodes `frames` (all the same size) as a looping GIF with `delay_cs` hundredths of a
/// second per frame. The renderer only writes colours of its fixed palette
/// ([`crate::palette`]), so frames are written with that global palette and no colour
/// quantization; any other colour maps to the nearest palette entry.
///
/// # Errors
/// [`RenderError::EmptyAnimation`] without frames, [`RenderError::GifSize`] if a frame is
/// larger than 65535 pixels either way or the frames differ in size, [`RenderError::Gif`]
/// if the encoder fails.
pub fn encode_gif(frames: &[Framebuffer], delay_cs: u16) -> Result<Vec<u8>, RenderError> {
    let first = frames.first().ok_or(RenderError::EmptyAnimation)?;
    let (w, h) = (first.width(), first.height());
    let size_error = || RenderError::GifSize {
        width: w,
        height: h,
    };
    let w16 = u16::try_from(w).map_err(|_| size_error())?;
    let h16 = u16::try_from(h).map_err(|_| size_error())?;
    let colors = palette();
    let flat: Vec<u8> = colors.iter().flat_map(|c| [c[0], c[1], c[2]]).collect();
    let mut lookup: Vec<(u32, u8)> = colors
        .iter()
        .enumerate()
        .map(|(i, c)| (key(*c), i as u8))
        .collect();
    lookup.sort_unstable();
    // Index and LZW-compress the frames in parallel (each independently, so the bytes do
    // not depend on scheduling), then write them in order.
    let encoded: Vec<Result<gif::Frame<'static>, RenderError>> = frames
        .par_iter()
        .map(|fb| {
            if fb.width() != w || fb.height() != h {
                return Err(size_error());
            }
            let mut last = (u32::MAX, 0u8);
            let indices: Vec<u8> = fb
                .pixels()
                .iter()
                .map(|&c| {
                    let k = key(c);
                    if k != last.0 {
                        last = (k, index_of(&lookup, &colors, c));
                    }
                    last.1
                })
                .collect();
            let mut frame = gif::Frame::from_indexed_pixels(w16, h16, indices, None);
            frame.delay = delay_cs;
            frame.make_lzw_pre_encoded();
            Ok(frame)
        })
        .collect();
    let mut out = Vec::new();
    {
        let mut enc = gif::Encoder::new(&mut out, w16, h16, &flat)?;
        enc.set_repeat(gif::Repeat::Infinite)?;
        for frame in encoded {
            enc.write_lzw_pre_encoded_frame(&frame?)?;
        }
        enc.into_inner()?;
    }
    Ok(out)
}

fn key(c: Rgba) -> u32 {
    u32::from_be_bytes(c)
}

/// The palette index of `c`: exact when it is a palette colour, else the nearest.
fn index_of(lookup: &[(u32, u8)], colors: &[Rgba], c: Rgba) -> u8 {
    if let Ok(i) = lookup.binary_search_by_key(&key(c), |e| e.0) {
        if let Some(e) = lookup.get(i) {
            return e.1;
        }
    }
    let dist = |p: &Rgba| -> i32 {
        (0..3)
            .map(|k| (i32::from(p[k]) - i32::from(c[k])).pow(2))
            .sum()
    };
    colors
        .iter()
        .enumerate()
        .min_by_key(|(_, p)| dist(p))
        .map_or(0, |(i, _)| i as u8)
}

/// Up to `max` indices out of `0..n`, evenly spread, first and last included (all of them
/// when `n <= max`).
pub fn pick_evenly(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    if max <= 1 {
        return vec![0; max.min(n)];
    }
    (0..max)
        .map(|k| (k * (n - 1) + (max - 1) / 2) / (max - 1))
        .collect()
}

/// Lays `frames` (all the size of the first) out in a grid of `ceil(sqrt(n))` columns,
/// row by row, on `background`. An empty list gives a 1x1 picture.
pub fn contact_sheet(frames: &[Framebuffer], background: Rgba) -> Framebuffer {
    let Some(first) = frames.first() else {
        return Framebuffer::color_only(1, 1, background);
    };
    let n = frames.len();
    let cols = (1..=n).find(|c| c * c >= n).unwrap_or(1);
    let rows = n.div_ceil(cols);
    let (w, h) = (first.width(), first.height());
    let mut sheet = Framebuffer::color_only(w * cols as u32, h * rows as u32, background);
    for (i, f) in frames.iter().enumerate() {
        sheet.blit(f, (i % cols) as u32 * w, (i / cols) as u32 * h);
    }
    sheet
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picks_spread_and_include_the_ends() {
        assert_eq!(pick_evenly(3, 16), vec![0, 1, 2]);
        assert_eq!(pick_evenly(100, 4), vec![0, 33, 66, 99]);
        let p = pick_evenly(1000, 16);
        assert_eq!((p.len(), p[0], p[15]), (16, 0, 999));
        assert!(p.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn gif_delay_rounds_and_clamps() {
        assert_eq!(gif_delay_cs(25.0), 4);
        assert_eq!(gif_delay_cs(30.0), 3);
        assert_eq!(gif_delay_cs(120.0), 2);
        assert_eq!(gif_delay_cs(0.0), 2);
    }

    #[test]
    fn sheet_is_a_grid() {
        let a = Framebuffer::new(4, 3, [1, 2, 3, 255]);
        let sheet = contact_sheet(&[a.clone(), a.clone(), a.clone(), a.clone(), a], [0; 4]);
        assert_eq!((sheet.width(), sheet.height()), (12, 6));
        assert_eq!(sheet.get(11, 5), Some([0; 4]));
        assert_eq!(sheet.get(5, 4), Some([1, 2, 3, 255]));
    }

    #[test]
    fn png_and_gif_encode() {
        let fb = Framebuffer::new(8, 8, crate::BACKGROUND);
        let png = encode_png(&fb).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        let gif = encode_gif(&[fb.clone(), fb.clone()], 4).unwrap();
        assert_eq!(&gif[..6], b"GIF89a");
        assert!(matches!(
            encode_gif(&[], 4),
            Err(RenderError::EmptyAnimation)
        ));
    }
}
