//! Issue 17: the readers are strict where the format is. Each case is a minimized input a
//! black-box fuzz found accepted (silently cut, or read leniently) before; each must now be an
//! error naming the file, the line (text formats) and what was expected, in plain words.
mod common;
use common::*;
use meshio::{Format, MeshIoError};

/// Read `text` from a temporary file named `name`; return the error message.
fn err(name: &str, text: &[u8]) -> String {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    let e = meshio::read(&p).expect_err(name);
    let s = e.to_string();
    assert!(s.contains(&p.display().to_string()), "names the file: {s}");
    for debug in ["ParseError", "LineCol", "ParseIntError", "kind:", "{ "] {
        assert!(!s.contains(debug), "no Rust Debug text ({debug}): {s}");
    }
    s
}

/// Read `text` as [`err`] does; the message must contain every `wanted` piece.
fn rejects(name: &str, text: &[u8], wanted: &[&str]) {
    let s = err(name, text);
    for w in wanted {
        assert!(s.contains(w), "{w:?} missing in: {s}");
    }
}

fn ok(name: &str, text: &[u8]) -> meshio::TriMesh {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    meshio::read(&p).unwrap_or_else(|e| panic!("{name}: {e}"))
}

const PLY_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n\
end_header\n";

fn ply(body: &str) -> Vec<u8> {
    format!("{PLY_HEAD}{body}").into_bytes()
}

#[test]
fn ply_ascii_valid_triangle_reads() {
    let m = ok("valid.ply", &ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
    // Blank lines and trailing blank lines are harmless; CRLF too.
    let crlf = ply("0 0 0\r\n\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n\n").to_vec();
    assert_eq!(ok("crlf.ply", &crlf), m);
}

#[test]
fn ply_ascii_vertex_with_an_extra_token_is_rejected() {
    // The header declares 3 properties; `0 0 1 9` has 4 values (was cut to 0 0 1).
    rejects(
        "extra_v.ply",
        &ply("0 0 0\n1 0 0\n0 0 1 9\n3 0 1 2\n"),
        &[
            "line 12: vertex 2 has 1 value(s) more",
            "float x, float y, float z",
        ],
    );
}

#[test]
fn ply_ascii_face_with_an_extra_index_is_rejected() {
    // `3 0 1 3 2`: the count says 3 indices, the line has 4.
    rejects(
        "extra_f.ply",
        &ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 3 2\n"),
        &["line 13: face 0 has 1 value(s) more"],
    );
}

#[test]
fn ply_ascii_space_inside_a_number_is_rejected() {
    // `0 1 -0 5` was `0 1 -0.5` with a space: z became 0 and 5 was dropped.
    rejects(
        "space.ply",
        &ply("0 0 0\n1 0 0\n0 1 -0 5\n3 0 1 2\n"),
        &["line 12: vertex 2 has 1 value(s) more"],
    );
    // A number cut the other way: too few values on the line.
    rejects(
        "short.ply",
        &ply("0 0 0\n1 0 0\n0 1\n3 0 1 2\n"),
        &["line 12: vertex 2 has too few values: property z is missing"],
    );
}

#[test]
fn ply_ascii_bad_tokens_name_line_and_property() {
    rejects(
        "tok.ply",
        &ply("0 0 0\n1 0x 0\n0 1 0\n3 0 1 2\n"),
        &["line 11: vertex 1, property y: \"0x\" is not a valid float value"],
    );
    // nan/inf are numbers (numpy and trimesh read them), but x, y and z must be finite.
    for (tok, shown) in [("nan", "NaN"), ("-INF", "-inf"), ("Infinity", "inf")] {
        rejects(
            "nan.ply",
            &ply(&format!("0 0 0\n1 {tok} 0\n0 1 0\n3 0 1 2\n")),
            &[&format!(
                "line 11: vertex 1, property y: {shown} is not a finite coordinate"
            )],
        );
    }
    rejects(
        "nanx.ply",
        &ply("0 0 0\n1 0 0\n0 1 0x\n3 0 1 2\n"),
        &["\"0x\" is not a valid float value"],
    );
    rejects(
        "idx.ply",
        &ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n"),
        &["line 13: face 0, property vertex_indices: \"2.5\" is not a valid int value"],
    );
    rejects(
        "count.ply",
        &ply("0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n"),
        &["\"300\" is not a valid uchar value"],
    );
}

#[test]
fn ply_data_after_the_last_element_is_rejected() {
    rejects(
        "more.ply",
        &ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n"),
        &["line 14: data after the last element"],
    );
    // Binary: bytes after the declared elements.
    let m = octahedron();
    let mut b = Vec::new();
    meshio::write_to(&mut b, &m, Format::Ply, meshio::Options::default(), "mem").unwrap();
    b.extend_from_slice(&[0, 0, 0]);
    rejects("more_bin.ply", &b, &["3 bytes after the last element"]);
}

#[test]
fn ply_ascii_too_few_lines_is_truncated() {
    let p = tmp("few.ply");
    std::fs::write(&p, ply("0 0 0\n1 0 0\n")).unwrap();
    let e = meshio::read(&p).unwrap_err();
    assert!(matches!(e, MeshIoError::Truncated { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("declares 3 vertex elements, the data ends after 2"),
        "{e}"
    );
}

#[test]
fn ply_format_version_other_than_1_0_is_rejected() {
    for v in ["2.0", "1.1", "0.9", "1"] {
        let text = PLY_HEAD.replace("ascii 1.0", &format!("ascii {v}"));
        let s = err(
            "ver.ply",
            format!("{text}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").as_bytes(),
        );
        assert!(
            s.contains(&format!(
                "PLY version {v} is not supported (only 1.0 exists)"
            )),
            "{s}"
        );
    }
}

#[test]
fn ply_header_errors_are_plain_words() {
    let cases: [(&str, &str); 7] = [
        ("format ascii 1.0", "format text 1.0"),
        ("property float y", "property flaot y"),
        ("element face 1", "element face -1"),
        ("element face 1", "element face one"),
        ("property float z", "propertyfloat z"),
        ("property float y", "property float x"),
        ("end_header", "end_header extra"),
    ];
    let expect = [
        "header line 2: expected 'format ascii|binary_little_endian|binary_big_endian 1.0'",
        "header line 5: unknown type \"flaot\"",
        "header line 7: element face: the count \"-1\" is not a non-negative integer",
        "header line 7: element face: the count \"one\" is not a non-negative integer",
        "header line 6: expected format, comment, obj_info, element, property or end_header",
        "header line 5: element vertex has a second property \"x\"",
        "header line 9: expected format, comment, obj_info, element, property or end_header",
    ];
    for ((from, to), want) in cases.iter().zip(expect) {
        let text = PLY_HEAD.replacen(from, to, 1);
        let s = err(
            "hdr.ply",
            format!("{text}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").as_bytes(),
        );
        assert!(s.contains(want), "{to}: {s}");
    }
    // No end_header: truncated, in words.
    let p = tmp("noend.ply");
    std::fs::write(&p, "ply\nformat ascii 1.0\nelement vertex 1\n").unwrap();
    let e = meshio::read(&p).unwrap_err();
    assert!(matches!(e, MeshIoError::Truncated { .. }), "{e}");
    assert!(e.to_string().contains("without end_header"), "{e}");
}

const STL_FACET: &str =
    "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";

fn stl(facets: &str) -> Vec<u8> {
    format!("solid t\n{facets}endsolid t\n").into_bytes()
}

#[test]
fn stl_ascii_valid_facets_read() {
    let m = ok("valid.stl", &stl(&STL_FACET.repeat(2)));
    assert_eq!(m.triangles.len(), 2);
    // Keywords are case-insensitive; several solids in one file are read in turn.
    let upper = STL_FACET.to_ascii_uppercase();
    let two = format!("solid a\n{upper}endsolid a\nsolid b\n{STL_FACET}endsolid\n");
    assert_eq!(ok("two.stl", two.as_bytes()).triangles.len(), 2);
}

#[test]
fn stl_ascii_garbled_keywords_are_rejected() {
    let cases = [
        (
            "outer loop",
            "outer lop",
            "line 3: facet 0: expected 'outer loop'",
        ),
        (
            "outer loop",
            "outerloop",
            "line 3: facet 0: expected 'outer loop'",
        ),
        (
            "facet normal",
            "facet nromal",
            "line 2: facet 0: expected 'facet normal",
        ),
        ("endloop", "end loop", "line 7: facet 0: expected 'endloop'"),
        (
            "endfacet",
            "endfacets",
            "line 8: facet 0: expected 'endfacet'",
        ),
        (
            "vertex 1 0 0",
            "vertex 1 0",
            "line 5: facet 0: expected 'vertex x y z'",
        ),
        (
            "vertex 1 0 0",
            "vertex 1 0 0 0",
            "line 5: facet 0: expected 'vertex x y z'",
        ),
        (
            "vertex 1 0 0",
            "vertex 1 O 0",
            "line 5: facet 0: expected 'vertex x y z'",
        ),
    ];
    for (from, to, want) in cases {
        let s = err("garbled.stl", &stl(&STL_FACET.replacen(from, to, 1)));
        assert!(s.contains(want), "{to}: {s}");
    }
}

#[test]
fn stl_ascii_facets_with_other_than_3_vertices_are_rejected() {
    let four = STL_FACET.replace("endloop", "vertex 1 1 0\nendloop");
    rejects(
        "quad.stl",
        &stl(&four),
        &["line 7: facet 0: expected 'endloop' (a facet has exactly 3 vertices)"],
    );
    let two = STL_FACET.replace("vertex 0 1 0\n", "");
    rejects(
        "two_vertices.stl",
        &stl(&two),
        &["line 6: facet 0: expected 'vertex x y z'"],
    );
}

#[test]
fn stl_ascii_without_endsolid_is_truncated() {
    let p = tmp("noend.stl");
    std::fs::write(&p, format!("solid t\n{STL_FACET}")).unwrap();
    let e = meshio::read(&p).unwrap_err();
    assert!(matches!(e, MeshIoError::Truncated { .. }), "{e}");
    assert!(e.to_string().contains("'endsolid [name]'"), "{e}");
}

#[test]
fn binary_stl_size_must_be_84_plus_50n() {
    let m = octahedron();
    let mut b = Vec::new();
    meshio::write_to(&mut b, &m, Format::Stl, meshio::Options::default(), "mem").unwrap();
    assert_eq!(b.len(), 84 + 50 * 8);
    b.push(0);
    rejects(
        "long.stl",
        &b,
        &["announces 8 facets, i.e. 84 + 50 * 8 = 484 bytes, but the file has 485"],
    );
    b.truncate(484 - 7);
    rejects("short.stl", &b, &["484 bytes), the file has 477 bytes"]);
}

const OBJ_V: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";

#[test]
fn obj_junk_in_face_corners_is_rejected() {
    for corner in [
        "5//-inf", "1/nan/1", "6/13/1/1", "1/", "1//", "1/0/1", "1/+/1", "x",
    ] {
        let text = format!("{OBJ_V}f 1 2 {corner}\n");
        let s = err("corner.obj", text.as_bytes());
        assert!(
            s.contains(&format!("line 6: bad face corner {corner:?}")),
            "{corner}: {s}"
        );
    }
    // Well-formed corners that refer to missing texture or normal lines.
    rejects(
        "vt.obj",
        format!("{OBJ_V}f 1/1 2/2 3/1\n").as_bytes(),
        &["line 6: a face corner refers to texture (vt) index 2, which does not exist"],
    );
    rejects(
        "vn.obj",
        format!("{OBJ_V}f 1//1 2//1 3//-2\n").as_bytes(),
        &["normal (vn) index -2"],
    );
    // The valid forms still read.
    let m = ok(
        "corners.obj",
        format!("{OBJ_V}f 1/1/1 2//1 3/-1\n").as_bytes(),
    );
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
}

#[test]
fn obj_vertex_lines_take_3_4_6_or_7_numbers() {
    // x y z, x y z w (w ignored), x y z r g b and x y z r g b a (colours ignored) read;
    // other counts and non-numbers are errors naming the line.
    for (v, valid) in [
        ("v 0 1 0 1 0", false),
        ("v 0 1", false),
        ("v 0 1 0 1 2 3 4 5", false),
        ("v 0 1 0 junk", false),
        ("v 0 1 0 1 nan 1", false),
        ("v 0 1 0", true),
        ("v 0 1 0 0.5", true),
        ("v 0 1 0 1 0.5 0", true),
        ("v 0 1 0 1 0.5 0 1", true),
    ] {
        let text = OBJ_V.replace("v 0 1 0", v) + "f 1 2 3\n";
        if valid {
            let m = ok("v.obj", text.as_bytes());
            assert_eq!(m.vertices[2], glam::DVec3::new(0.0, 1.0, 0.0), "{v}");
        } else {
            let s = err("v.obj", text.as_bytes());
            assert!(s.contains("line 3: "), "{v}: {s}");
        }
    }
}

const OFF_TRI: &str = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

#[test]
fn off_counts_and_tokens_are_checked() {
    let cases = [
        (
            "3 1 0\n",
            "3 1 0 7\n",
            "line 2: expected the counts 'nv nf ne'",
        ),
        (
            "3 1 0\n",
            "3 x 0\n",
            "line 2: expected the counts 'nv nf ne'",
        ),
        (
            "3 1 0\n",
            "-3 1 0\n",
            "line 2: expected the counts 'nv nf ne'",
        ),
        (
            "1 0 0\n",
            "1 0 0 9\n",
            "line 4: vertex 1: expected 'x y z' (numbers)",
        ),
        (
            "1 0 0\n",
            "1 0\n",
            "line 4: vertex 1: expected 'x y z' (numbers)",
        ),
        (
            "1 0 0\n",
            "1 0 0x\n",
            "line 4: vertex 1: expected 'x y z' (numbers)",
        ),
        (
            "3 0 1 2\n",
            "3 0 1 2 9 9\n",
            "line 6: face 0: expected 3 integer indices",
        ),
        (
            "3 0 1 2\n",
            "3 0 1 2.5\n",
            "line 6: face 0: expected 3 integer indices",
        ),
        (
            "3 0 1 2\n",
            "3 0 1\n",
            "line 6: face 0: expected 3 integer indices",
        ),
        (
            "3 0 1 2\n",
            "3 0 1 2\n3 0 2 1\n",
            "line 7: data after the last face",
        ),
        ("OFF\n", "XOFF\n", "line 1: expected an OFF header"),
    ];
    for (from, to, want) in cases {
        let s = err("bad.off", OFF_TRI.replacen(from, to, 1).as_bytes());
        assert!(s.contains(want), "{to:?}: {s}");
    }
    // Valid variants: counts without ne, face colours, COFF vertex colours, NOFF normals.
    for text in [
        OFF_TRI.replace("3 1 0\n", "3 1\n"),
        OFF_TRI.replace("3 0 1 2\n", "3 0 1 2 255 0 0\n"),
        OFF_TRI.replace("3 0 1 2\n", "3 0 1 2 0.5 0.5 0.5 1\n"),
        "COFF\n3 1 0\n0 0 0 255 0 0\n1 0 0 0 255 0 255\n0 1 0 0 0 255\n3 0 1 2\n".to_string(),
        OFF_TRI
            .replace("OFF\n", "NOFF\n")
            .replace("0 0 0\n", "0 0 0 0 0 1\n")
            .replace("1 0 0\n", "1 0 0 0 0 1\n")
            .replace("0 1 0\n", "0 1 0 0 0 1\n"),
    ] {
        let m = ok("good.off", text.as_bytes());
        assert_eq!(m.triangles, vec![[0, 1, 2]], "{text}");
        assert_eq!(m.vertices[1], glam::DVec3::X, "{text}");
    }
}

/// Asserts that `OBJ_V` (five lines), then `line` (line 6), then a face, read as `file`,
/// is rejected with an error containing `msg`, for each of `lines`.
fn assert_line_6_rejected(file: &str, lines: &[&str], msg: &str) {
    for line in lines {
        let text = format!("{OBJ_V}{line}\nf 1 2 3\n");
        let s = err(file, text.as_bytes());
        assert!(s.contains(msg), "{line}: {s}");
    }
}

/// scripts/mutate.py found these accepted with exit 0: a garbled keyword after the first
/// statement was ignored (`f/ 1 2 3`, `1//1 2//2 3//3`, `vertex 1 2 3`: a face or vertex
/// silently dropped), and `vt` / `vn` lines were not read (`vn 0 0 double`).
#[test]
fn obj_unknown_statements_and_bad_vt_vn_are_rejected() {
    let statements = [
        "f/ 1 2 3",
        "f// 1 2 3",
        "1//1 2//2 3//3",
        "vertex 1 2 3",
        "OFF",
        "11865475",
    ];
    assert_line_6_rejected("kw.obj", &statements, "line 6: unknown OBJ statement");
    let vt_vn = [
        "vn 0 0 double",
        "vn 0 0",
        "vn 0 0 1 1",
        "vn 0 nan 1",
        "vt",
        "vt 0 0 0 0",
        "vt x",
    ];
    assert_line_6_rejected("vtvn.obj", &vt_vn, "line 6: expected 'v");
    // The specification's other statements and well-formed vt / vn lines still read.
    let text = format!(
        "{OBJ_V}vt 0.5\nvt 0 1\nvn 0 0 1\ng a\ns off\nusemtl m\nlod 1\nbevel off\n\
         f 1/1/1 2/2/1 3/1/1\n"
    );
    assert_eq!(ok("spec.obj", text.as_bytes()).triangles, vec![[0, 1, 2]]);
}

/// scripts/mutate.py: `v 0 -0.70 0.70710678118#65475` read as z = 0.70710678118 (the `#`
/// inside the number started a comment). A `#` starts a comment only at the start of a line
/// or after white space; inside a token it makes the token bad.
#[test]
fn obj_and_off_hash_inside_a_number_is_not_a_comment() {
    let text = OBJ_V.replace("v 0 1 0", "v 0 1 0.70710678118#65475") + "f 1 2 3\n";
    let s = err("hash.obj", text.as_bytes());
    assert!(
        s.contains("line 3: ") && s.contains("0.70710678118#65475"),
        "{s}"
    );
    let off = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0.5#5\n3 0 1 2\n";
    let s = err("hash.off", off.as_bytes());
    assert!(s.contains("line 5: ") && s.contains("0.5#5"), "{s}");
    // Comments after white space, and whole-line comments, still work.
    let text = format!("# c\n{OBJ_V}f 1 2 3 # a face\n#\n");
    assert_eq!(
        ok("hash_ok.obj", text.as_bytes()).triangles,
        vec![[0, 1, 2]]
    );
    let off = "OFF # header\n3 1 0\n0 0 0\t# a\n1 0 0\n0 1 0\n3 0 1 2 #\n";
    assert_eq!(ok("hash_ok.off", off.as_bytes()).triangles, vec![[0, 1, 2]]);
}

/// issue 17: NaN or inf in a float property other than x, y, z (trimesh reads them) is read,
/// its value ignored; the mesh is the same as without the property.
#[test]
fn ply_non_finite_values_of_other_properties_are_ignored() {
    let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nproperty float nx\nproperty float quality\nproperty uchar red\n\
element face 1\nproperty list uchar int vertex_indices\nproperty float quality\nend_header\n";
    let body = "0 0 0 nan inf 1\n1 0 0 -inf NaN 2\n0 1 0 0 Infinity 3\n3 0 1 2 nan\n";
    let m = ok("other-nan.ply", format!("{head}{body}").as_bytes());
    let plain = ok("plain.ply", &ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
    assert_eq!(m, plain);
    // A non-finite normal: the point set is read, its normals ignored (estimated instead).
    let head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n";
    let p = tmp("normals-nan.ply");
    std::fs::write(&p, format!("{head}0 0 0 0 0 1\n1 0 0 nan 0 1\n")).unwrap();
    let c = meshio::read_point_cloud(&p).unwrap();
    assert_eq!(c.points.len(), 2);
    assert!(c.normals.is_none());
    std::fs::write(&p, format!("{head}0 0 0 0 0 1\n1 0 0 0 1 0\n")).unwrap();
    assert_eq!(
        meshio::read_point_cloud(&p).unwrap().normals.unwrap().len(),
        2
    );
}
