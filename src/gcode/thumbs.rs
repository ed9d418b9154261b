//! PNG and QOI thumbnails of a toolpath, drawn by the core so the page and the CLI write the same bytes
//! ([`super::Printer::thumbnails`]). The view is the page's example pictures' (turned 45° about
//! Z, tilted), each path in its feature's preview colour ([`Feature::color`]), lower layers
//! darker (the top layer in the colour itself), on a transparent background; paths are drawn
//! in print order, so what is printed later covers what is under it.
//!
//! Bounded: the projected length drawn is at most [`MAX_DRAWN_PX`] pixels and 10 times the
//! picture's area (whole passes are skipped evenly past it, the top one always kept), points
//! under half a pixel apart are drawn as one, and the picture is at most
//! [`super::MAX_THUMBNAIL_PX`] a side. The PNG is 8-bit RGBA, deflated with `miniz_oxide`
//! (already in the tree for the share links) and checksummed with `crc32fast` (in the tree
//! through `flate2`): the format's three chunks are a few lines, and a PNG crate would add
//! crates to the page's module for them.

use crate::geom::{Feature, Toolpath};

/// Most pixels of line drawn per picture (sum of the projected lengths).
pub const MAX_DRAWN_PX: f64 = 1.5e6;
/// Tilt of the view: 0 = straight from above, 1 = isometric.
const TILT: f64 = 0.6;

/// The PNG of `toolpath` at `width` × `height` px (at least 1, at most
/// [`super::MAX_THUMBNAIL_PX`]).
pub fn png(toolpath: &Toolpath, width: u32, height: u32) -> Vec<u8> {
    let (w, h) = (width.clamp(1, super::MAX_THUMBNAIL_PX), height.clamp(1, super::MAX_THUMBNAIL_PX));
    encode(w, h, &rgba(toolpath, w, h))
}

/// The same picture as [`png`], as a QOI image (8-bit RGBA, the format's own encoding: what
/// Prusa's xBuddy screens decode).
pub fn qoi(toolpath: &Toolpath, width: u32, height: u32) -> Vec<u8> {
    let (w, h) = (width.clamp(1, super::MAX_THUMBNAIL_PX), height.clamp(1, super::MAX_THUMBNAIL_PX));
    // The pixels are w × h × 4 bytes by construction, the one thing the encoder checks.
    qoi::encode_to_vec(rgba(toolpath, w, h), w, h).unwrap_or_default()
}

fn project(x: f64, y: f64, z: f64) -> (f64, f64) {
    let r = std::f64::consts::FRAC_1_SQRT_2;
    ((x - y) * r, -((x + y) * r * (1.0 - 0.5 * TILT) + z * TILT))
}

fn rgb(hex: &str) -> [u8; 3] {
    let v = u32::from_str_radix(hex.trim_start_matches('#'), 16).unwrap_or(0xbebebe);
    [(v >> 16) as u8, (v >> 8) as u8, v as u8]
}

/// The picture's pixels, RGBA rows top to bottom.
pub fn rgba(toolpath: &Toolpath, w: u32, h: u32) -> Vec<u8> {
    let (wu, hu) = (w as usize, h as usize);
    let mut img = vec![0u8; wu * hu * 4];
    let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    let (mut zlo, mut zhi) = (f64::INFINITY, f64::NEG_INFINITY);
    for pass in &toolpath.passes {
        for p in pass.paths.iter().filter(|p| p.points.len() >= 2) {
            for q in &p.points {
                let (u, v) = project(q.x, q.y, q.z);
                lo = (lo.0.min(u), lo.1.min(v));
                hi = (hi.0.max(u), hi.1.max(v));
                zlo = zlo.min(q.z);
                zhi = zhi.max(q.z);
            }
        }
    }
    if !(lo.0.is_finite() && hi.0.is_finite() && lo.1.is_finite() && hi.1.is_finite() && zlo.is_finite() && zhi.is_finite()) {
        return img;
    }
    let margin = 0.04 * f64::from(w.min(h));
    let span = ((hi.0 - lo.0) / (f64::from(w) - 2.0 * margin)).max((hi.1 - lo.1) / (f64::from(h) - 2.0 * margin));
    let scale = if span > 0.0 { 1.0 / span } else { 1.0 };
    let ox = (f64::from(w) - (hi.0 - lo.0) * scale) / 2.0;
    let oy = (f64::from(h) - (hi.1 - lo.1) * scale) / 2.0;
    let to_px = |x: f64, y: f64, z: f64| {
        let (u, v) = project(x, y, z);
        (ox + (u - lo.0) * scale, oy + (v - lo.1) * scale)
    };
    // Passes drawn: every `step`-th from the top, so the drawn length stays under the cap (and
    // under 10 times the picture's area: a small picture needs few layers).
    let cap = MAX_DRAWN_PX.min(10.0 * f64::from(w) * f64::from(h));
    let drawn_px: f64 = toolpath.passes.iter().flat_map(|p| &p.paths).map(|p| p.length() * scale).sum();
    let step = if drawn_px > cap { (drawn_px / cap).ceil() as usize } else { 1 };
    let n = toolpath.passes.len();
    let dz = zhi - zlo;
    for (k, pass) in toolpath.passes.iter().enumerate() {
        if (n - 1 - k) % step != 0 {
            continue;
        }
        for p in pass.paths.iter().filter(|p| p.points.len() >= 2) {
            let base = rgb(p.feature.color());
            let thick = (p.width * scale).clamp(1.0, 6.0);
            // Points closer than half a pixel to the last one drawn are passed over.
            let q = p.points[0];
            let mut a = to_px(q.x, q.y, q.z);
            let last = p.points.len() - 1;
            for (i, q) in p.points.iter().enumerate().skip(1) {
                let b = to_px(q.x, q.y, q.z);
                if i < last && (b.0 - a.0).abs() + (b.1 - a.1).abs() < 0.5 {
                    continue;
                }
                let shade = if dz > 0.0 { 0.45 + 0.55 * ((q.z - zlo) / dz).clamp(0.0, 1.0) } else { 1.0 };
                let c = base.map(|x| (f64::from(x) * shade).round() as u8);
                line(&mut img, wu, hu, a, b, thick, c);
                a = b;
            }
        }
    }
    img
}

/// A line of `thick` px from `a` to `b`: squares of that side stamped every 0.7 side (at least
/// every half pixel), so the work is about 1.4 × the length times the thickness.
fn line(img: &mut [u8], w: usize, h: usize, a: (f64, f64), b: (f64, f64), thick: f64, c: [u8; 3]) {
    let len = ((b.0 - a.0) * (b.0 - a.0) + (b.1 - a.1) * (b.1 - a.1)).sqrt();
    let n = (len / (thick * 0.7).max(0.5)).ceil().max(1.0) as usize;
    let r = thick / 2.0;
    for k in 0..=n {
        let t = k as f64 / n as f64;
        let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        let (x0, x1) = ((x - r).round().max(0.0) as usize, ((x + r).round() as usize).min(w));
        let (y0, y1) = ((y - r).round().max(0.0) as usize, ((y + r).round() as usize).min(h));
        let px = [c[0], c[1], c[2], 255];
        let xe = x1.max(x0 + 1).min(w);
        if x0 >= xe {
            continue;
        }
        for yy in y0..y1.max(y0 + 1).min(h) {
            for p in img[(yy * w + x0) * 4..(yy * w + xe) * 4].chunks_exact_mut(4) {
                p.copy_from_slice(&px);
            }
        }
    }
}

/// 8-bit RGBA PNG of `rgba` (rows top to bottom), no filter.
pub fn encode(w: u32, h: u32, rgba: &[u8]) -> Vec<u8> {
    let row = w as usize * 4;
    let mut raw = Vec::with_capacity((row + 1) * h as usize);
    for r in rgba.chunks(row.max(1)).take(h as usize) {
        raw.push(0);
        raw.extend_from_slice(r);
    }
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::with_capacity(13);
    ihdr.extend(w.to_be_bytes());
    ihdr.extend(h.to_be_bytes());
    ihdr.extend([8, 6, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(&mut out, b"IDAT", &miniz_oxide::deflate::compress_to_vec_zlib(&raw, 6));
    chunk(&mut out, b"IEND", &[]);
    out
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend((data.len() as u32).to_be_bytes());
    out.extend(kind);
    out.extend(data);
    let mut crc = crc32fast::Hasher::new();
    crc.update(kind);
    crc.update(data);
    out.extend(crc.finalize().to_be_bytes());
}

/// The feature colours a thumbnail uses, `[r, g, b]` at full shade (the top layer's).
pub fn colors() -> Vec<[u8; 3]> {
    Feature::ALL.iter().map(|f| rgb(f.color())).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Pass, Path};
    use glam::DVec3;

    fn part() -> Toolpath {
        let sq = |z: f64| {
            let p = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]].map(|q| DVec3::new(q[0], q[1], z));
            Path::new(p.to_vec(), Feature::ExternalPerimeter, 0.4)
        };
        Toolpath { passes: (1..=5).map(|k| Pass::layer(k as f64 * 0.2, 0.2, vec![sq(k as f64 * 0.2)])).collect() }
    }

    #[test]
    fn a_png_of_the_asked_size_in_the_feature_colour() {
        let png = png(&part(), 40, 24);
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        assert_eq!(&png[16..24], &[0, 0, 0, 40, 0, 0, 0, 24]);
        let img = rgba(&part(), 40, 24);
        let top = rgb(Feature::ExternalPerimeter.color());
        assert!(img.chunks(4).any(|p| p[..3] == top && p[3] == 255));
        assert!(img.chunks(4).any(|p| p[3] == 0), "the background is transparent");
        assert_eq!(png, super::png(&part(), 40, 24), "same bytes twice");
    }

    #[test]
    fn nothing_to_draw_is_transparent() {
        assert!(rgba(&Toolpath::default(), 8, 8).iter().all(|b| *b == 0));
    }
}
