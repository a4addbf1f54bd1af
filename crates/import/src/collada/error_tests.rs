//! COLLADA importer tests: one per error class, each with its line (and column and
//! element where the class has one).

use std::path::Path;

use super::tests::{dae, error_of, line_of, skinned};
use super::*;

#[test]
fn bad_xml_is_located_at_its_line_and_column() {
    let text = "<?xml version=\"1.0\"?>\n<COLLADA>\n  <asset>\n  </assit>\n</COLLADA>\n";
    let e = error_of(text);
    assert!(e.to_string().starts_with("t.dae:4:"), "{e}");
    assert!(e.to_string().contains("not well-formed XML"), "{e}");
}

#[test]
fn a_truncated_file_is_truncated_at_its_last_line() {
    let text = skinned("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1");
    let cut = &text[..text.len() / 2];
    let lines = cut.trim_end().lines().count();
    let e = error_of(cut);
    assert!(matches!(e.problem, Problem::Truncated(_)), "{e}");
    assert_eq!(e.location.line, Some(lines), "{e}");
}

#[test]
fn a_missing_id_is_named_at_the_element_that_refers_to_it() {
    let text =
        skinned("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1").replace("source=\"#quad\"", "source=\"#geom\"");
    let e = error_of(&text);
    let line = line_of(&text, "source=\"#geom\"");
    let column = 1 + text
        .lines()
        .nth(line - 1)
        .and_then(|l| l.find("<skin"))
        .unwrap_or(0);
    assert_eq!(
        e.location.to_string(),
        format!("t.dae:{line}:{column}: element <skin>"),
        "{e}"
    );
    assert!(e.to_string().contains("\"#geom\""), "{e}");
}

#[test]
fn wrong_counts_are_errors_at_the_array_or_accessor() {
    let text = skinned("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1")
        .replace("count=\"12\">0 0 0", "count=\"13\">0 0 0");
    let e = error_of(&text);
    assert_eq!(e.location.line, Some(line_of(&text, "count=\"13\"")), "{e}");
    assert_eq!(e.location.element.as_deref(), Some("float_array"), "{e}");
    assert!(matches!(e.problem, Problem::Count { found: 12, .. }), "{e}");
    // An accessor that reads past its array.
    let text = skinned("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1")
        .replace("source=\"#pa\" count=\"4\"", "source=\"#pa\" count=\"5\"");
    let e = error_of(&text);
    assert_eq!(e.location.element.as_deref(), Some("accessor"), "{e}");
    // Too few vertex weight rows for the geometry's vertices.
    let text = skinned("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1")
        .replace("<vcount>1 1 1 1</vcount>", "<vcount>1 1 1</vcount>");
    let e = error_of(&text);
    assert_eq!(e.location.element.as_deref(), Some("vcount"), "{e}");
    // An index past its source.
    let text = skinned("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1")
        .replace("<p>0 1 2 0 2 3</p>", "<p>0 1 2 0 2 7</p>");
    let e = error_of(&text);
    assert!(
        matches!(
            e.problem,
            Problem::IndexOutOfRange {
                index: 7,
                count: 4,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn an_empty_or_cyclic_skeleton_is_an_error() {
    let text = skinned("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1")
        .replace(
            "<Name_array id=\"jna\" count=\"1\">J</Name_array>",
            "<Name_array id=\"jna\" count=\"0\"></Name_array>",
        )
        .replace("source=\"#jna\" count=\"1\"", "source=\"#jna\" count=\"0\"");
    let e = error_of(&text);
    assert_eq!(e.location.element.as_deref(), Some("joints"), "{e}");
    assert!(e.to_string().contains("empty"), "{e}");
    let text = dae(
        "",
        "<library_nodes><node id=\"a\"><instance_node url=\"#b\"/></node>\
         <node id=\"b\"><instance_node url=\"#a\"/></node></library_nodes>\n\
         <library_visual_scenes><visual_scene id=\"s\"><node id=\"top\"><instance_node url=\"#a\"/></node>\
         </visual_scene></library_visual_scenes>",
    );
    let e = error_of(&text);
    assert!(e.to_string().contains("cyclic"), "{e}");
    assert_eq!(e.location.element.as_deref(), Some("instance_node"), "{e}");
}

#[test]
fn a_document_that_is_not_collada_or_is_empty_is_refused() {
    let e = error_of("<?xml version=\"1.0\"?>\n<svg/>\n");
    assert!(e.to_string().contains("not <COLLADA>"), "{e}");
    assert!(matches!(error_of(" \n").problem, Problem::Empty));
}

#[test]
fn a_zae_without_a_dae_is_refused() {
    use std::io::Write;
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut zip = zip::ZipWriter::new(&mut buf);
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored);
        zip.start_file("readme.txt", options).expect("zip");
        zip.write_all(b"no document").expect("zip");
        zip.finish().expect("zip");
    }
    let e = match import_slice(buf.get_ref(), Path::new("t.zae")) {
        Ok(_) => panic!("imported a package without a document"),
        Err(e) => e,
    };
    assert!(e.to_string().contains("holds no .dae"), "{e}");
}
