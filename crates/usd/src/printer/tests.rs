use super::*;

#[test]
fn prints_the_usdcat_layout() {
    let mut p = UsdaPrinter::new(String::new());
    p.begin_layer(&[Field::new("upAxis", "Z".into())]);
    p.begin_prim(
        Specifier::Def,
        Some("Mesh"),
        "M",
        &[Field::prepend(
            "apiSchemas",
            Value::List(vec!["A".into(), "B".into()]),
        )],
    );
    p.attribute(
        AttrDecl::new("normal3f[]", "normals"),
        Some(Data::Float3s(&[[0.0, -0.0, 1.0]])),
        &[Field::new("interpolation", "vertex".into())],
    );
    p.begin_time_samples(AttrDecl::uniform("float[]", "w"));
    p.time_sample(1.5, Data::Floats(&[0.1, 1e-8]));
    p.end_time_samples();
    p.blank_line();
    p.begin_variant_set("v");
    p.begin_variant(
        "a",
        &[Field::new(
            "customData",
            Value::Dict(vec![("x".into(), 1.0.into())]),
        )],
    );
    p.end_variant();
    p.end_variant_set();
    p.end_prim();
    assert_eq!(
        p.into_inner(),
        r#"#usda 1.0
(
    upAxis = "Z"
)

def Mesh "M" (
    prepend apiSchemas = ["A", "B"]
)
{
    normal3f[] normals = [(0, -0, 1)] (
        interpolation = "vertex"
    )
    uniform float[] w.timeSamples = {
        1.5: [0.1, 0.00000001],
    }

    variantSet "v" = {
        "a" (
            customData = {
                double x = 1
            }
        ) {
        }
    }
}
"#
    );
}

#[test]
fn strings_are_escaped_and_matrices_printed_by_rows() {
    let mut s = String::new();
    quoted(&mut s, "a\"b\\c\nd");
    assert_eq!(s, r#""a\"b\\c\nd""#);
    let mut s = String::new();
    let mut m = [0.0; 16];
    m[0] = 1.0;
    m[12] = 2.0;
    data(&mut s, &Data::Matrix4(m));
    assert_eq!(
        s,
        "( (1, 0, 0, 0), (0, 0, 0, 0), (0, 0, 0, 0), (2, 0, 0, 0) )"
    );
}
