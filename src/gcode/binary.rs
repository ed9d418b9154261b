//! Text G-code → Prusa binary G-code ([`super::bgcode`]): the thumbnails' comment blocks
//! become thumbnail blocks, the `; key = value` comments become the metadata blocks (the keys a
//! printer reads before printing in the printer metadata, the totals in the print metadata,
//! all of them in the slicer metadata), and the rest of the text is the G-code. Works on any
//! file written in PrusaSlicer's convention, weft's own included, so the page, the CLI and
//! `weft send` give the same bytes for the same text.

use super::bgcode::{encode, Input, Thumbnail, ThumbnailFormat};
use base64::Engine;

/// Keys of the printer metadata block (what a Prusa printer checks before it prints).
const PRINTER_KEYS: &[&str] = &[
    "printer_model",
    "filament_type",
    "nozzle_diameter",
    "bed_temperature",
    "temperature",
    "layer_height",
    "max_layer_z",
    "filament used [mm]",
    "filament used [g]",
    "estimated printing time (normal mode)",
];

/// Keys of the print metadata block (the totals).
const PRINT_KEYS: &[&str] = &[
    "filament used [mm]",
    "filament used [cm3]",
    "filament used [g]",
    "total filament used [g]",
    "estimated printing time (normal mode)",
    "total layers count",
];

/// The line opening a thumbnail block of `format` in text G-code (PrusaSlicer's), up to its size.
pub fn begin_tag(format: ThumbnailFormat) -> &'static str {
    match format {
        ThumbnailFormat::Png => "; thumbnail begin ",
        ThumbnailFormat::Qoi => "; thumbnail_QOI begin ",
    }
}

/// The line closing a thumbnail block of `format`.
pub fn end_tag(format: ThumbnailFormat) -> &'static str {
    match format {
        ThumbnailFormat::Png => "; thumbnail end",
        ThumbnailFormat::Qoi => "; thumbnail_QOI end",
    }
}

/// The `.bgcode` bytes of `text`. Only the text up to the end of its last thumbnail block is
/// copied (the blocks left out); the rest is encoded where it lies, so a large file is not held
/// twice.
pub fn from_text(text: &str) -> Vec<u8> {
    let mut head = String::new();
    let mut thumbnails = Vec::new();
    let mut meta: Vec<(String, String)> = Vec::new();
    let mut thumb: Option<(u16, u16, ThumbnailFormat, String)> = None;
    // The head's length before the open block's preceding text was added.
    let mut open_head = 0;
    // Where the last thumbnail block ends: the text before it is rewritten into `head`.
    let mut head_end = 0;
    let mut at = 0;
    for line in text.split_inclusive('\n') {
        at += line.len();
        let body = line.trim_end_matches(['\n', '\r']);
        if let Some((w, h, format, b64)) = &mut thumb {
            if body.trim() == end_tag(*format) {
                if let Ok(image) = base64::engine::general_purpose::STANDARD.decode(b64.as_bytes()) {
                    thumbnails.push(Thumbnail { width: *w, height: *h, format: *format, image });
                }
                thumb = None;
                head_end = at;
            } else {
                b64.push_str(body.trim_start_matches(';').trim());
            }
            continue;
        }
        let begun = [ThumbnailFormat::Png, ThumbnailFormat::Qoi].into_iter().find_map(|f| Some((f, body.strip_prefix(begin_tag(f))?)));
        if let Some((format, rest)) = begun {
            let size = rest.split_whitespace().next().unwrap_or("");
            if let Some((w, h)) = size.split_once('x') {
                if let (Ok(w), Ok(h)) = (w.parse(), h.parse()) {
                    // The text since the last block joins the head.
                    open_head = head.len();
                    head.push_str(&text[head_end..at - line.len()]);
                    thumb = Some((w, h, format, String::new()));
                    continue;
                }
            }
        }
        if let Some((k, v)) = body.strip_prefix("; ").and_then(|c| c.split_once(" = ")) {
            if !k.is_empty() && !meta.iter().any(|(key, _)| key == k) {
                meta.push((k.to_string(), v.to_string()));
            }
        }
    }
    // A block that never ends is no thumbnail: from the last one's end on, the text is kept.
    if thumb.is_some() {
        head.truncate(open_head);
    }
    let pick = |keys: &[&str]| -> Vec<(String, String)> { keys.iter().filter_map(|k| meta.iter().find(|(key, _)| key == k).cloned()).collect() };
    let file = vec![("Producer".to_string(), format!("weft {}", env!("CARGO_PKG_VERSION")))];
    encode(&Input {
        file_metadata: &file,
        printer_metadata: &pick(PRINTER_KEYS),
        thumbnails: &thumbnails,
        print_metadata: &pick(PRINT_KEYS),
        slicer_metadata: &meta,
        gcode: &head,
        gcode_more: &text[head_end..],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thumbnails_and_keys_leave_the_text() {
        let png = super::super::thumbs::encode(2, 2, &[255; 16]);
        let b64 = base64::engine::general_purpose::STANDARD.encode(&png);
        let text = format!("; generated by weft\n; thumbnail begin 2x2 {}\n; {b64}\n; thumbnail end\nG1 X1 Y2 E.5\n; layer_height = 0.2\n", b64.len());
        let b = from_text(&text);
        assert_eq!(&b[..4], b"GCDE");
        // The PNG is stored as is, in a thumbnail block.
        assert!(b.windows(png.len()).any(|w| w == png.as_slice()));
        assert!(b.windows(b"layer_height=0.2".len()).any(|w| w == b"layer_height=0.2"));
        assert_eq!(from_text(&text), b, "same bytes twice");
        // A block that never ends is text, kept once.
        let open = format!("{text}; thumbnail begin 2x2 99\n; abc\nG1 X9\n");
        let ob = from_text(&open);
        assert_eq!(ob.windows(png.len()).filter(|w| *w == png.as_slice()).count(), 1);
    }
}
