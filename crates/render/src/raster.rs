//! The framebuffer and the primitives drawn into it: z-buffered triangles, lines, discs,
//! rings and a 3x5 digit font.
//!
//! Screen space: pixel `(x, y)` covers `[x, x + 1) x [y, y + 1)`, `y` grows downwards, pixel
//! centres sit at `+0.5`. Depth grows towards the viewer (larger is nearer).

/// An RGBA8 colour (straight alpha; the renderer only writes opaque colours).
pub type Rgba = [u8; 4];

/// An RGBA8 picture with a depth buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct Framebuffer {
    width: u32,
    height: u32,
    /// `width * height` colours, row by row from the top.
    color: Vec<Rgba>,
    /// `width * height` depths; larger is nearer, `f32::NEG_INFINITY` where nothing was drawn.
    depth: Vec<f32>,
}

impl Framebuffer {
    /// A `width` x `height` picture filled with `background` and an empty depth buffer.
    pub fn new(width: u32, height: u32, background: Rgba) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            color: vec![background; n],
            depth: vec![f32::NEG_INFINITY; n],
        }
    }

    /// A `width` x `height` picture filled with `background` and no depth buffer, for
    /// compositing ([`Framebuffer::blit`], overlays) at half the memory: triangles drawn
    /// into it write nothing.
    pub fn color_only(width: u32, height: u32, background: Rgba) -> Self {
        Self {
            width,
            height,
            color: vec![background; width as usize * height as usize],
            depth: Vec::new(),
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The colours, `width * height`, row by row from the top.
    pub fn pixels(&self) -> &[Rgba] {
        &self.color
    }

    /// The colour at `(x, y)`, `None` outside the picture.
    pub fn get(&self, x: u32, y: u32) -> Option<Rgba> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.color
            .get(y as usize * self.width as usize + x as usize)
            .copied()
    }

    /// Sets pixel `(x, y)` to `color` regardless of depth; ignored outside the picture.
    pub fn put(&mut self, x: i64, y: i64, color: Rgba) {
        if x < 0 || y < 0 || x >= i64::from(self.width) || y >= i64::from(self.height) {
            return;
        }
        let i = y as usize * self.width as usize + x as usize;
        if let Some(c) = self.color.get_mut(i) {
            *c = color;
        }
    }

    /// Copies `src` into this picture with its top-left corner at `(x0, y0)`, clipped.
    pub fn blit(&mut self, src: &Framebuffer, x0: u32, y0: u32) {
        for y in 0..src.height {
            for x in 0..src.width {
                if let Some(c) = src.get(x, y) {
                    self.put(i64::from(x0 + x), i64::from(y0 + y), c);
                }
            }
        }
    }

    /// Fills the triangle with screen-space corners `p` (`[x, y, depth]`) in `color`,
    /// keeping the nearer surface per pixel. Both windings are drawn (two-sided). A pixel is
    /// covered when its centre is inside the triangle; centres exactly on an edge count for
    /// top and left edges only (the Direct3D / OpenGL fill rule), so two triangles sharing an
    /// edge cover each pixel once. Returns the number of pixels written.
    pub fn triangle(&mut self, p: [[f32; 3]; 3], color: Rgba) -> usize {
        self.triangle_shaded(p, |_| color)
    }

    /// As [`Framebuffer::triangle`], colouring each covered pixel with `shader` of its
    /// barycentric weights (one per corner of `p`, in `p`'s order, summing to 1; linear in
    /// screen space).
    pub fn triangle_shaded(
        &mut self,
        p: [[f32; 3]; 3],
        mut shader: impl FnMut([f32; 3]) -> Rgba,
    ) -> usize {
        let [a, b, c] = p;
        let area = edge(a, b, c[0], c[1]);
        if !area.is_finite() || area == 0.0 {
            return 0;
        }
        // Make the winding positive so one inside test serves both windings.
        let swapped = area < 0.0;
        let (b, c, area) = if swapped { (c, b, -area) } else { (b, c, area) };
        let w = self.width as f32;
        let h = self.height as f32;
        let min_x = a[0].min(b[0]).min(c[0]).floor().max(0.0);
        let max_x = a[0].max(b[0]).max(c[0]).ceil().min(w);
        let min_y = a[1].min(b[1]).min(c[1]).floor().max(0.0);
        let max_y = a[1].max(b[1]).max(c[1]).ceil().min(h);
        if min_x >= max_x || min_y >= max_y {
            return 0;
        }
        // In this winding (clockwise on screen), an edge is a top or left edge when it runs
        // upwards, or exactly horizontally to the right.
        let top_left = |p: [f32; 3], q: [f32; 3]| -> bool {
            let dy = q[1] - p[1];
            dy < 0.0 || (dy == 0.0 && q[0] > p[0])
        };
        let (tl0, tl1, tl2) = (top_left(b, c), top_left(c, a), top_left(a, b));
        let inside = |w: f32, tl: bool| w > 0.0 || (w == 0.0 && tl);
        let inv_area = 1.0 / area;
        let width = self.width as usize;
        let mut written = 0;
        for y in (min_y as u32)..(max_y as u32) {
            let py = y as f32 + 0.5;
            for x in (min_x as u32)..(max_x as u32) {
                let px = x as f32 + 0.5;
                let w0 = edge(b, c, px, py);
                let w1 = edge(c, a, px, py);
                let w2 = edge(a, b, px, py);
                if !(inside(w0, tl0) && inside(w1, tl1) && inside(w2, tl2)) {
                    continue;
                }
                let z = (w0 * a[2] + w1 * b[2] + w2 * c[2]) * inv_area;
                let i = y as usize * width + x as usize;
                if let (Some(d), Some(col)) = (self.depth.get_mut(i), self.color.get_mut(i)) {
                    if z > *d {
                        *d = z;
                        let (wb, wc) = (w1 * inv_area, w2 * inv_area);
                        let weights = if swapped {
                            [w0 * inv_area, wc, wb]
                        } else {
                            [w0 * inv_area, wb, wc]
                        };
                        *col = shader(weights);
                        written += 1;
                    }
                }
            }
        }
        written
    }

    /// Draws a line `thickness` pixels wide from `a` to `b` (screen space) on top of
    /// everything, ignoring depth.
    pub fn line(&mut self, a: [f32; 2], b: [f32; 2], thickness: u32, color: Rgba) {
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        if !len.is_finite() {
            return;
        }
        // Step at most half a pixel so the stamped squares overlap into a solid line.
        let steps = (len * 2.0).ceil().clamp(1.0, 1e5) as u32;
        let half = thickness as f32 / 2.0;
        for s in 0..=steps {
            let t = s as f32 / steps as f32;
            let x = a[0] + (b[0] - a[0]) * t;
            let y = a[1] + (b[1] - a[1]) * t;
            let x0 = (x - half).round() as i64;
            let y0 = (y - half).round() as i64;
            for dy in 0..i64::from(thickness) {
                for dx in 0..i64::from(thickness) {
                    self.put(x0 + dx, y0 + dy, color);
                }
            }
        }
    }

    /// Draws a filled disc of `radius` pixels centred at `c` (screen space) on top of
    /// everything, ignoring depth.
    pub fn disc(&mut self, c: [f32; 2], radius: f32, color: Rgba) {
        self.ring(c, 0.0, radius, color);
    }

    /// Draws the ring of pixels whose centres lie between `inner` and `outer` pixels from `c`
    /// (screen space) on top of everything, ignoring depth.
    pub fn ring(&mut self, c: [f32; 2], inner: f32, outer: f32, color: Rgba) {
        if !(c[0].is_finite() && c[1].is_finite() && inner.is_finite() && outer.is_finite()) {
            return;
        }
        let r1 = outer.clamp(0.0, 1e4);
        let r0 = inner.clamp(0.0, r1);
        let x0 = (c[0] - r1).floor() as i64;
        let x1 = (c[0] + r1).ceil() as i64;
        let y0 = (c[1] - r1).floor() as i64;
        let y1 = (c[1] + r1).ceil() as i64;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let dx = x as f32 + 0.5 - c[0];
                let dy = y as f32 + 0.5 - c[1];
                let d2 = dx * dx + dy * dy;
                if d2 >= r0 * r0 && d2 <= r1 * r1 {
                    self.put(x, y, color);
                }
            }
        }
    }

    /// Writes the decimal `number` with the built-in 3x5 font (see [`Framebuffer::text`]).
    pub fn number(&mut self, number: u64, x: i64, y: i64, scale: u32, color: Rgba) {
        self.text(&number.to_string(), x, y, scale, color);
    }

    /// Writes `text` with the built-in 3x5 font (digits, the letters of `LBS`/`DQS`, and
    /// `.`, `-`, `E`, `M` for a scale's numbers; other characters leave a gap), each font pixel `scale` x `scale` screen pixels,
    /// top-left corner at `(x, y)`, one font pixel between characters.
    pub fn text(&mut self, text: &str, x: i64, y: i64, scale: u32, color: Rgba) {
        let s = i64::from(scale.max(1));
        for (k, ch) in text.bytes().enumerate() {
            let Some(glyph) = glyph(ch) else {
                continue;
            };
            let gx = x + k as i64 * 4 * s;
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..3 {
                    if bits & (0b100 >> col) != 0 {
                        for dy in 0..s {
                            for dx in 0..s {
                                self.put(gx + col * s + dx, y + row as i64 * s + dy, color);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// The 3x5 glyph of `ch`, if the font has one.
fn glyph(ch: u8) -> Option<&'static [u8; 5]> {
    match ch {
        b'0'..=b'9' => DIGITS.get(usize::from(ch - b'0')),
        b'L' => Some(&[0b100, 0b100, 0b100, 0b100, 0b111]),
        b'B' => Some(&[0b110, 0b101, 0b110, 0b101, 0b110]),
        b'S' => Some(&[0b111, 0b100, 0b111, 0b001, 0b111]),
        b'D' => Some(&[0b110, 0b101, 0b101, 0b101, 0b110]),
        b'Q' => Some(&[0b010, 0b101, 0b101, 0b110, 0b011]),
        // A colour scale's numbers: "1.5E-3", "MM".
        b'.' => Some(&[0b000, 0b000, 0b000, 0b000, 0b010]),
        b'-' => Some(&[0b000, 0b000, 0b111, 0b000, 0b000]),
        b'E' => Some(&[0b111, 0b100, 0b110, 0b100, 0b111]),
        b'M' => Some(&[0b101, 0b111, 0b111, 0b101, 0b101]),
        _ => None,
    }
}

/// The 3x5 digit font: per digit five rows, top first, three bits each (MSB = left).
const DIGITS: [[u8; 5]; 10] = [
    [0b111, 0b101, 0b101, 0b101, 0b111],
    [0b010, 0b110, 0b010, 0b010, 0b111],
    [0b111, 0b001, 0b111, 0b100, 0b111],
    [0b111, 0b001, 0b111, 0b001, 0b111],
    [0b101, 0b101, 0b111, 0b001, 0b001],
    [0b111, 0b100, 0b111, 0b001, 0b111],
    [0b111, 0b100, 0b111, 0b101, 0b111],
    [0b111, 0b001, 0b010, 0b010, 0b010],
    [0b111, 0b101, 0b111, 0b101, 0b111],
    [0b111, 0b101, 0b111, 0b001, 0b111],
];

/// Twice the signed area of `(a, b, p)`: positive when `p` is to the left of `a -> b` in a
/// y-up frame (to the right on screen, where y grows downwards).
fn edge(a: [f32; 3], b: [f32; 3], px: f32, py: f32) -> f32 {
    (b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    const BG: Rgba = [0, 0, 0, 255];
    const RED: Rgba = [255, 0, 0, 255];
    const BLUE: Rgba = [0, 0, 255, 255];

    fn count(fb: &Framebuffer, c: Rgba) -> usize {
        fb.pixels().iter().filter(|&&p| p == c).count()
    }

    #[test]
    fn right_triangle_covers_half_its_box() {
        // Legs of 100 px: area 5000 px^2; pixel-centre sampling is exact to about one edge
        // length of pixels (100) at most.
        for corners in [
            [[10.0, 10.0, 0.0], [110.0, 10.0, 0.0], [10.0, 110.0, 0.0]],
            [[10.0, 10.0, 0.0], [10.0, 110.0, 0.0], [110.0, 10.0, 0.0]],
        ] {
            let mut fb = Framebuffer::new(128, 128, BG);
            let n = fb.triangle(corners, RED);
            assert_eq!(n, count(&fb, RED));
            assert!((4900..=5100).contains(&n), "{n} pixels");
        }
    }

    #[test]
    fn shared_edge_is_covered_once() {
        // A square split along its diagonal: exactly 64 x 64 pixels, none twice.
        let mut fb = Framebuffer::new(80, 80, BG);
        let a = fb.triangle([[8.0, 8.0, 0.0], [72.0, 8.0, 0.0], [72.0, 72.0, 0.0]], RED);
        let b = fb.triangle([[8.0, 8.0, 0.0], [72.0, 72.0, 0.0], [8.0, 72.0, 0.0]], RED);
        assert_eq!(a + b, 64 * 64);
        assert_eq!(count(&fb, RED), 64 * 64);
    }

    #[test]
    fn depth_keeps_the_nearer_triangle_in_either_order() {
        let far = [[0.0, 0.0, -1.0], [64.0, 0.0, -1.0], [0.0, 64.0, -1.0]];
        let near = [[0.0, 0.0, 1.0], [64.0, 0.0, 1.0], [0.0, 64.0, 1.0]];
        let mut fb = Framebuffer::new(64, 64, BG);
        fb.triangle(far, RED);
        fb.triangle(near, BLUE);
        assert_eq!(count(&fb, RED), 0);
        let blue = count(&fb, BLUE);
        assert!(blue > 1900, "{blue}");
        let mut fb2 = Framebuffer::new(64, 64, BG);
        fb2.triangle(near, BLUE);
        assert_eq!(fb2.triangle(far, RED), 0);
        assert_eq!(fb, fb2);
    }

    #[test]
    fn degenerate_and_offscreen_triangles_draw_nothing() {
        let mut fb = Framebuffer::new(16, 16, BG);
        assert_eq!(
            fb.triangle([[1.0, 1.0, 0.0], [5.0, 5.0, 0.0], [9.0, 9.0, 0.0]], RED),
            0
        );
        assert_eq!(
            fb.triangle(
                [
                    [-50.0, -50.0, 0.0],
                    [-10.0, -50.0, 0.0],
                    [-50.0, -10.0, 0.0]
                ],
                RED
            ),
            0
        );
        assert_eq!(
            fb.triangle(
                [[f32::NAN, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 5.0, 0.0]],
                RED
            ),
            0
        );
        assert_eq!(count(&fb, RED), 0);
    }

    #[test]
    fn ring_leaves_its_middle_and_clips_at_the_border() {
        let mut fb = Framebuffer::new(32, 32, BG);
        fb.ring([16.0, 16.0], 4.0, 6.0, RED);
        assert_eq!(fb.get(16, 16), Some(BG));
        assert_eq!(fb.get(16 + 4, 16), Some(RED));
        assert_eq!(fb.get(16 + 7, 16), Some(BG));
        // Area between the circles is about pi (36 - 16) = 63 pixels.
        assert!((55..=71).contains(&count(&fb, RED)), "{}", count(&fb, RED));
        // Partly outside, or not finite: no panic, only pixels inside drawn.
        fb.ring([0.0, 0.0], 2.0, 50.0, BLUE);
        fb.ring([f32::NAN, 0.0], 2.0, 5.0, BLUE);
        assert!(count(&fb, BLUE) > 0);
    }

    #[test]
    fn digits_draw_inside_their_box() {
        let mut fb = Framebuffer::new(32, 16, BG);
        fb.number(18, 1, 1, 2, RED);
        // "1" has 8 lit cells, "8" has 13; each is 2x2 pixels.
        assert_eq!(count(&fb, RED), (8 + 13) * 4);
        assert!((0..32).all(|x| fb.get(x, 0) == Some(BG)));
    }

    #[test]
    fn labels_use_their_own_glyphs_and_skip_unknown_characters() {
        let lit = |text: &str| {
            let mut fb = Framebuffer::new(16, 8, BG);
            fb.text(text, 1, 1, 1, RED);
            count(&fb, RED)
        };
        // L 7 + B 10 + S 11 cells; D 10 + Q 9 + S 11.
        assert_eq!(lit("LBS"), 7 + 10 + 11);
        assert_eq!(lit("DQS"), 10 + 9 + 11);
        assert_eq!(lit("x?"), 0);
    }
}
