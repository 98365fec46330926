//! Bad input never panics: random bytes, and every truncation of valid files, give Ok or a
//! typed error.
mod common;
use common::*;
use meshio::{Format, Options};
use proptest::prelude::*;

const FORMATS: [Format; 4] = [Format::Ply, Format::Off, Format::Obj, Format::Stl];

#[test]
fn every_truncation_of_every_format_is_handled() {
    let m = octahedron();
    for format in FORMATS {
        for binary in [false, true] {
            let mut bytes = Vec::new();
            meshio::write_to(
                &mut bytes,
                &m,
                format,
                Options {
                    binary,
                    double: true,
                },
                "mem",
            )
            .unwrap();
            for cut in 0..bytes.len() {
                if let Ok(back) = meshio::read_from(&bytes[..cut], format, "cut") {
                    // A prefix may parse (text formats without counts): it is then valid.
                    back.validate().unwrap();
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        for format in FORMATS {
            if let Ok(m) = meshio::read_from(&bytes[..], format, "random") {
                m.validate().unwrap();
            }
        }
    }

    #[test]
    fn corrupted_files_never_panic(pos in any::<prop::sample::Index>(), byte in any::<u8>(), k in 0usize..8) {
        let m = octahedron();
        let (format, binary) = [
            (Format::Ply, true), (Format::Ply, false), (Format::Off, false), (Format::Obj, false),
            (Format::Stl, true), (Format::Stl, false), (Format::Ply, true), (Format::Stl, true),
        ][k];
        let mut bytes = Vec::new();
        meshio::write_to(&mut bytes, &m, format, Options { binary, double: true }, "mem").unwrap();
        let i = pos.index(bytes.len());
        bytes[i] = byte;
        if let Ok(back) = meshio::read_from(&bytes[..], format, "corrupt") {
            back.validate().unwrap();
        }
    }
}
