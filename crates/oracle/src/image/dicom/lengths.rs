//! Declared value lengths checked against the file before the parser reads it (ours: input
//! hygiene for the reader of section 6.6.2's images; DICOM PS3.5 7.1 data element encoding,
//! 7.5 nesting of data sets, A.4 encapsulated pixel data).
//!
//! `dicom-object` reserves and zero-fills a value's declared length before it reads the value:
//! a damaged 9 KB file declaring a 4 GB pixel data element took 4.2 GB of memory and 5.6 s to
//! refuse (and would be killed where memory is short). This walk reads the element headers
//! only, the file meta group and the data set (sequences, items and fragments included), and
//! refuses a defined length longer than what is left of the file or of its enclosing item.
//!
//! Invariant: it refuses only a length that no reading can satisfy; where the encoding is
//! anything it does not follow (a deflated data set, an unexpected tag inside a sequence, over
//! [`MAX_DEPTH`] levels of nesting, a header cut by the end of the file), it stops checking and
//! leaves the file to the parser, which reads or refuses it as before.

use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry};
use dicom_core::{Tag, VR};
use dicom_dictionary_std::StandardDataDictionary;

/// Nesting deeper than this is left to the parser.
const MAX_DEPTH: usize = 32;

/// An undefined length (a sequence or item closed by a delimiter).
const UNDEFINED: u32 = u32::MAX;

/// How the data set's headers are encoded.
#[derive(Clone, Copy, PartialEq)]
enum Encoding {
    ExplicitLe,
    ImplicitLe,
    ExplicitBe,
}

/// What a walk found: the position after what it walked, or a reason to stop checking.
type Walk = Result<Option<usize>, String>;

/// Checks `bytes`, a DICOM file after its 128-byte preamble and `DICM` magic. The error is the
/// detail for the message: which element declares how many bytes and how many remain.
pub(crate) fn check(bytes: &[u8]) -> Result<(), String> {
    let reader = Reader {
        bytes,
        enc: Encoding::ExplicitLe,
    };
    // The file meta group (PS3.10 7.1): explicit VR little endian, group 0002.
    let mut pos = 0;
    let mut syntax = String::new();
    while let Some(h) = reader.header(pos) {
        if h.tag.group() != 0x0002 {
            break;
        }
        let end = h.value_end(pos, bytes.len())?;
        let Some(end) = end else { return Ok(()) };
        if h.tag == Tag(0x0002, 0x0010) {
            syntax = String::from_utf8_lossy(&bytes[h.start(pos)..end])
                .trim_end_matches(['\0', ' '])
                .to_string();
        }
        pos = end;
    }
    let enc = match syntax.as_str() {
        "1.2.840.10008.1.2" => Encoding::ImplicitLe,
        "1.2.840.10008.1.2.2" => Encoding::ExplicitBe,
        // Deflated: the data set's bytes are not the ones the parser reads.
        "1.2.840.10008.1.2.1.99" => return Ok(()),
        _ => Encoding::ExplicitLe,
    };
    let reader = Reader { bytes, enc };
    reader.data_set(pos, bytes.len(), 0, false).map(|_| ())
}

/// One element header: its tag, VR (explicit, or from the dictionary) and length.
struct Header {
    tag: Tag,
    vr: Option<VR>,
    len: u32,
    /// Bytes of the header (8 or 12).
    size: usize,
}

impl Header {
    fn start(&self, pos: usize) -> usize {
        pos + self.size
    }

    /// The end of a defined-length value within `limit`, an error when it would pass it;
    /// `None` for an undefined length.
    fn value_end(&self, pos: usize, limit: usize) -> Result<Option<usize>, String> {
        if self.len == UNDEFINED {
            return Ok(None);
        }
        let start = self.start(pos);
        let left = limit.saturating_sub(start);
        if self.len as usize > left {
            return Err(format!(
                "element ({:04X},{:04X}) declares {} bytes where {left} remain",
                self.tag.group(),
                self.tag.element(),
                self.len
            ));
        }
        Ok(Some(start + self.len as usize))
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    enc: Encoding,
}

impl Reader<'_> {
    fn u16_at(&self, at: usize, big: bool) -> u16 {
        let b = [self.bytes[at], self.bytes[at + 1]];
        if big {
            u16::from_be_bytes(b)
        } else {
            u16::from_le_bytes(b)
        }
    }

    fn u32_at(&self, at: usize, big: bool) -> u32 {
        let b: [u8; 4] = self.bytes[at..at + 4].try_into().unwrap_or([0; 4]);
        if big {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        }
    }

    /// The header at `pos` (`None`: fewer bytes than a header).
    fn header(&self, pos: usize) -> Option<Header> {
        if pos + 8 > self.bytes.len() {
            return None;
        }
        let big = self.enc == Encoding::ExplicitBe;
        let tag = Tag(self.u16_at(pos, big), self.u16_at(pos + 2, big));
        if tag.group() == 0xFFFE || self.enc == Encoding::ImplicitLe {
            // Items and delimiters have no VR; implicit VR takes it from the dictionary.
            let vr = (tag.group() != 0xFFFE)
                .then(|| StandardDataDictionary.by_tag(tag).map(|e| e.vr().relaxed()))
                .flatten();
            return Some(Header {
                tag,
                vr,
                len: self.u32_at(pos + 4, big),
                size: 8,
            });
        }
        let vr = VR::from_binary([self.bytes[pos + 4], self.bytes[pos + 5]])?;
        let long = matches!(
            vr,
            VR::OB
                | VR::OD
                | VR::OF
                | VR::OL
                | VR::OV
                | VR::OW
                | VR::SQ
                | VR::SV
                | VR::UC
                | VR::UN
                | VR::UR
                | VR::UT
                | VR::UV
        );
        if long {
            if pos + 12 > self.bytes.len() {
                return None;
            }
            Some(Header {
                tag,
                vr: Some(vr),
                len: self.u32_at(pos + 8, big),
                size: 12,
            })
        } else {
            Some(Header {
                tag,
                vr: Some(vr),
                len: self.u16_at(pos + 6, big) as u32,
                size: 8,
            })
        }
    }

    /// The elements from `pos` to `end` (an item of undefined length ends at its delimiter:
    /// `delimited`).
    fn data_set(&self, mut pos: usize, end: usize, depth: usize, delimited: bool) -> Walk {
        if depth > MAX_DEPTH {
            return Ok(None);
        }
        while pos < end {
            let Some(h) = self.header(pos) else {
                return Ok(None);
            };
            if h.tag == Tag(0xFFFE, 0xE00D) && delimited {
                return Ok(Some(pos + 8));
            }
            if h.tag.group() == 0xFFFE {
                return Ok(None);
            }
            let start = h.start(pos);
            let sequence = h.vr == Some(VR::SQ);
            pos = match h.value_end(pos, end)? {
                Some(value_end) if sequence => {
                    match self.items(start, value_end, depth + 1, false)? {
                        Some(_) => value_end,
                        None => return Ok(None),
                    }
                }
                Some(value_end) => value_end,
                None => {
                    let fragments = h.tag == Tag(0x7FE0, 0x0010);
                    match self.items(start, end, depth + 1, fragments)? {
                        Some(p) => p,
                        None => return Ok(None),
                    }
                }
            };
        }
        Ok(Some(pos))
    }

    /// The items of a sequence from `pos` (within `end`), to its delimiter or `end`;
    /// `fragments`: encapsulated pixel data, whose items hold bytes, not data sets.
    fn items(&self, mut pos: usize, end: usize, depth: usize, fragments: bool) -> Walk {
        if depth > MAX_DEPTH {
            return Ok(None);
        }
        while pos < end {
            let Some(h) = self.header(pos) else {
                return Ok(None);
            };
            match (h.tag.group(), h.tag.element()) {
                (0xFFFE, 0xE0DD) => return Ok(Some(pos + 8)),
                (0xFFFE, 0xE000) => {}
                _ => return Ok(None),
            }
            let start = h.start(pos);
            pos = match h.value_end(pos, end)? {
                Some(item_end) if fragments => item_end,
                Some(item_end) => match self.data_set(start, item_end, depth + 1, false)? {
                    Some(_) => item_end,
                    None => return Ok(None),
                },
                None if fragments => return Ok(None),
                None => match self.data_set(start, end, depth + 1, true)? {
                    Some(p) => p,
                    None => return Ok(None),
                },
            };
        }
        Ok(Some(pos))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An explicit VR little endian element.
    fn element(
        group: u16,
        elem: u16,
        vr: &[u8; 2],
        value: &[u8],
        declared: Option<u32>,
    ) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend(group.to_le_bytes());
        out.extend(elem.to_le_bytes());
        out.extend(vr);
        let len = declared.unwrap_or(value.len() as u32);
        if matches!(vr, b"OB" | b"OW" | b"SQ" | b"UN" | b"UT") {
            out.extend([0, 0]);
            out.extend(len.to_le_bytes());
        } else {
            out.extend((len as u16).to_le_bytes());
        }
        out.extend(value);
        out
    }

    fn file(data_set: &[u8], syntax: &[u8]) -> Vec<u8> {
        let mut f = element(0x0002, 0x0010, b"UI", syntax, None);
        f.extend(data_set);
        f
    }

    #[test]
    fn a_length_past_the_end_is_refused_and_exact_files_pass() {
        let name = element(0x0010, 0x0010, b"PN", b"Doe^J ", None);
        let pixels = element(0x7FE0, 0x0010, b"OW", &[0; 16], None);
        let good = file(
            &[name.clone(), pixels.clone()].concat(),
            b"1.2.840.10008.1.2.1\0",
        );
        assert_eq!(check(&good), Ok(()));
        let blown = element(0x7FE0, 0x0010, b"OW", &[0; 16], Some(0xFFFF_FFF0));
        let bad = file(&[name, blown].concat(), b"1.2.840.10008.1.2.1\0");
        let e = check(&bad).unwrap_err();
        assert!(
            e.contains("(7FE0,0010) declares 4294967280 bytes where 16 remain"),
            "{e}"
        );
    }

    #[test]
    fn nested_items_are_checked_within_their_item() {
        // A sequence of undefined length holding an item of defined length whose element
        // declares more than the item holds.
        let inner = element(0x0018, 0x0050, b"DS", b"1.0 ", Some(400));
        let mut item = vec![0xFE, 0xFF, 0x00, 0xE0];
        item.extend((inner.len() as u32).to_le_bytes());
        item.extend(&inner);
        let mut seq = element(0x5200, 0x9229, b"SQ", &[], Some(UNDEFINED));
        seq.extend(&item);
        seq.extend([0xFE, 0xFF, 0xDD, 0xE0, 0, 0, 0, 0]);
        seq.extend(element(0x7FE0, 0x0010, b"OW", &[0; 600], None));
        let e = check(&file(&seq, b"1.2.840.10008.1.2.1\0")).unwrap_err();
        assert!(e.contains("(0018,0050) declares 400 bytes"), "{e}");
    }

    #[test]
    fn what_the_walk_does_not_follow_is_left_to_the_parser() {
        // Deflated, and a header cut by the end of the file.
        let blown = element(0x7FE0, 0x0010, b"OW", &[], Some(0xFFFF_FFF0));
        assert_eq!(check(&file(&blown, b"1.2.840.10008.1.2.1.99")), Ok(()));
        assert_eq!(
            check(&file(&[0x10, 0x00, 0x10], b"1.2.840.10008.1.2.1\0")),
            Ok(())
        );
    }
}
