//! Share links: the whole design in the URL fragment, `#d=` + base64url(deflate(JSON)) (the
//! codec: [`crate::design::share`]), with each slot's file inside while they fit.

pub use crate::design::share::{
    pack, unpack, unpack_limited, Error, FRAGMENT_KEY, MAX_EMBEDDED_CHARS, MAX_EMBED_BYTES, MAX_FRAGMENT_CHARS, MAX_INFLATED_BYTES,
};
use crate::design::{Design, Input};

/// A share link's fragment and what it holds.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ShareLink {
    /// `#d=…`, to put after the page URL.
    pub fragment: String,
    /// Files inside the link.
    pub embedded: Vec<String>,
    /// Files the design names that are not inside the link (too large, or not loaded).
    pub missing: Vec<String>,
    /// Plain-language note for the user ("" when nothing to say).
    pub note: String,
}

/// Makes a link fragment for `design`. `files` are the loaded files (name, bytes); each
/// slot's file travels inside the link while the files embedded so far stay within
/// [`MAX_EMBED_BYTES`] in total (slots in the job kind's order); the others are listed in
/// [`ShareLink::missing`] and named in the note.
pub fn encode(design: &Design, files: &[(&str, &[u8])]) -> ShareLink {
    let mut value = serde_json::to_value(design).unwrap_or_default();
    let mut embedded = Vec::new();
    let mut missing = Vec::new();
    let mut used = 0usize;
    let registry = crate::kinds::Registry::builtin();
    let slots = registry.get(design.job.kind()).map(|k| k.slots()).unwrap_or(&[]);
    for slot in slots {
        match design.job.input_at(slot.path) {
            Some(Input::File { name, embedded: already }) => {
                let packed = match files.iter().find(|(n, _)| *n == name) {
                    Some((_, bytes)) if used + bytes.len() <= MAX_EMBED_BYTES => {
                        used += bytes.len();
                        Some(pack(bytes))
                    }
                    Some(_) => None,
                    None => already,
                };
                match packed {
                    Some(p) => {
                        embedded.push(name.clone());
                        let _ =
                            crate::design::set_path(&mut value, slot.path, serde_json::to_value(Input::File { name, embedded: Some(p) }).unwrap_or_default());
                    }
                    None => missing.push(name),
                }
            }
            Some(Input::Files(names)) => missing.extend(names),
            _ => {}
        }
    }
    let note = if missing.is_empty() {
        String::new()
    } else {
        let sizes: Vec<String> = missing
            .iter()
            .map(|n| match files.iter().find(|(f, _)| f == n) {
                Some((_, b)) => format!("{n} ({})", human_bytes(b.len())),
                None => n.clone(),
            })
            .collect();
        format!(
            "{} not in the link (files travel inside a link up to {} KiB in total); whoever opens it must load {}",
            sizes.join(", "),
            MAX_EMBED_BYTES / 1024,
            if missing.len() == 1 { "it" } else { "them" }
        )
    };
    let json = serde_json::to_string(&value).unwrap_or_default();
    ShareLink { fragment: format!("#{FRAGMENT_KEY}{}", pack(json.as_bytes())), embedded, missing, note }
}

/// Reads a design from a link fragment (with or without the leading `#`, or a whole URL).
pub fn decode(fragment: &str) -> Result<Design, Error> {
    let frag = fragment.rsplit_once('#').map_or(fragment, |(_, f)| f).trim();
    if frag.len() > MAX_FRAGMENT_CHARS {
        return Err(Error::TooLong { chars: frag.len() });
    }
    let data = frag.split('&').find_map(|kv| kv.strip_prefix(FRAGMENT_KEY)).ok_or(Error::Missing)?;
    let bytes = unpack_limited(data, crate::design::MAX_DESIGN_BYTES)?;
    let text = std::str::from_utf8(&bytes).map_err(|_| Error::Damaged)?;
    Ok(Design::from_json("share link", text)?)
}

fn human_bytes(n: usize) -> String {
    if n >= 1 << 20 {
        format!("{:.1} MB", n as f64 / (1u64 << 20) as f64)
    } else {
        format!("{} KiB", n.div_ceil(1024))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let d = Design::default();
        let link = encode(&d, &[]);
        assert!(link.fragment.starts_with("#d="));
        assert_eq!(decode(&link.fragment).unwrap(), d);
        assert_eq!(decode(&format!("http://localhost/www/{}", link.fragment)).unwrap(), d);
    }

    #[test]
    fn small_mesh_is_embedded_and_large_is_not() {
        let registry = crate::kinds::Registry::builtin();
        let d = Design::default().with_slot_input(&registry, "mesh", Input::File { name: "part.stl".into(), embedded: None }).unwrap();
        let small = vec![7u8; 1000];
        let link = encode(&d, &[("part.stl", &small)]);
        assert!(link.embedded == ["part.stl"] && link.missing.is_empty() && link.note.is_empty());
        let back = decode(&link.fragment).unwrap();
        let Some(Input::File { embedded: Some(e), .. }) = back.job.input_at("job.input") else { panic!() };
        assert_eq!(unpack(&e).unwrap(), small);
        let big = vec![1u8; MAX_EMBED_BYTES + 1];
        let link = encode(&d, &[("part.stl", &big)]);
        assert!(link.embedded.is_empty() && link.missing == ["part.stl"]);
        assert!(link.note.contains("part.stl") && link.note.contains("256 KiB"), "{}", link.note);
        // Two slots share one limit: the solid fits, the surface after it does not.
        let mut l = Design::from_json("t", include_str!("../../examples/honeycomb-10mm.json")).unwrap();
        l = l.with_slot_input(&registry, "mesh", Input::File { name: "a.stl".into(), embedded: None }).unwrap();
        l = l.with_overrides(&[r#"job.surface_input={"file":{"name":"b.stl"}}"#.into()]).unwrap();
        let a = vec![3u8; MAX_EMBED_BYTES - 10];
        let b = vec![4u8; 100];
        let link = encode(&l, &[("a.stl", &a), ("b.stl", &b)]);
        assert_eq!((link.embedded, link.missing), (vec!["a.stl".to_string()], vec!["b.stl".to_string()]));
    }

    #[test]
    fn damaged_links_say_what_to_do_in_words() {
        let damaged = "this link is damaged: it was cut short or changed while copying; ask for the link again";
        // Base64 of a wrong length or with an impossible last character, data that does not
        // inflate, a design that is not text: all the same to the user.
        for frag in ["#d=abcdefghij", "#d=abcdefghijn", "#d=abcdefghijk", "#d=AAAA"] {
            assert_eq!(decode(frag).unwrap_err().to_string(), damaged, "{frag}");
        }
        assert_eq!(decode(&format!("#d={}", pack(&[0xff, 0xfe, 0x80]))).unwrap_err().to_string(), damaged);
        let link = encode(&Design::default(), &[]);
        assert_eq!(decode(&link.fragment[..link.fragment.len() - 7]).unwrap_err().to_string(), damaged);
        assert_eq!(
            decode("#d=ab cd").unwrap_err().to_string(),
            "this link is damaged: character 3 of its design (a space) cannot be in a link, so the link was changed while copying; copy the whole link again"
        );
        assert_eq!(
            decode("#d=ab%20cd").unwrap_err().to_string(),
            "this link is damaged: character 3 of its design ('%') cannot be in a link, so the link was changed while copying; copy the whole link again"
        );
        assert_eq!(decode("https://x.org/#x=1").unwrap_err().to_string(), "this link has no design in it (a weft link ends in '#d=…'); ask for the link again");
        let bomb = pack(&vec![b' '; crate::design::MAX_DESIGN_BYTES + 10]);
        assert_eq!(
            decode(&format!("#d={bomb}")).unwrap_err().to_string(),
            "this link unpacks to more than 4194304 bytes, the limit for a design: it is not a weft link, or it was altered; ask for the link again or share the design file"
        );
        let mut v = serde_json::to_value(Design::default()).unwrap();
        v["job"]["slice"]["perimeters"] = 2.5.into();
        let frag = format!("#d={}", pack(v.to_string().as_bytes()));
        assert_eq!(decode(&frag).unwrap_err().to_string(), "share link: job.slice.perimeters: Perimeters must be a whole number from 0 to 50 (got 2.5)");
    }

    #[test]
    fn damaged_links_say_so() {
        assert!(matches!(decode("#d=!!!!"), Err(Error::Character { position: 1, found: '!' })));
        assert!(matches!(decode("#x=abc"), Err(Error::Missing)));
        assert!(matches!(decode("#d=AAAA"), Err(Error::Damaged)));
        let link = encode(&Design::default(), &[]);
        let cut = &link.fragment[..link.fragment.len() / 2];
        assert!(decode(cut).is_err());
        let long = format!("#d={}", "A".repeat(MAX_FRAGMENT_CHARS + 1));
        assert!(matches!(decode(&long), Err(Error::TooLong { .. })));
        // A deflate bomb is refused, not inflated.
        let bomb = pack(&vec![b' '; MAX_INFLATED_BYTES + 10]);
        assert!(matches!(decode(&format!("#d={bomb}")), Err(Error::TooBig { .. })));
    }
}
