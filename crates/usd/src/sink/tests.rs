use std::path::Path;

use super::*;
use crate::layer::PrimSpec;
use crate::parse::parse;
use crate::printer::UsdaPrinter;

/// A stage with every kind of call, described once.
fn stage(sink: &mut dyn LayerSink) {
    sink.begin_layer(&[
        Field::new("defaultPrim", "Root".into()),
        Field::new("doc", "a \"doc\"".into()),
        Field::new("metersPerUnit", 0.01.into()),
    ]);
    sink.begin_prim(
        Specifier::Def,
        Some("SkelRoot"),
        "Root",
        &[
            Field::new(
                "variants",
                Value::Dict(vec![("clip".into(), "walk".into())]),
            ),
            Field::prepend("variantSets", "clip".into()),
        ],
    );
    sink.attribute(
        AttrDecl::new("matrix4d", "xformOp:transform"),
        Some(Data::Matrix4([
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.5, 2.0, 3.0, 1.0,
        ])),
        &[],
    );
    sink.attribute(
        AttrDecl::uniform("token[]", "xformOpOrder"),
        Some(Data::Strs(&["xformOp:transform"])),
        &[],
    );
    sink.blank_line();
    sink.begin_prim(
        Specifier::Def,
        Some("Mesh"),
        "M",
        &[Field::prepend(
            "apiSchemas",
            Value::List(vec!["SkelBindingAPI".into()]),
        )],
    );
    sink.attribute(
        AttrDecl::new("point3f[]", "points"),
        Some(Data::Float3s(&[[0.1, -0.5, 1e-8], [1.0, 2.0, 3.0]])),
        &[],
    );
    sink.begin_time_samples(AttrDecl::new("point3f[]", "points"));
    sink.time_sample(0.0, Data::Float3s(&[[0.1, 0.2, 0.3]]));
    sink.time_sample(2.5, Data::Float3s(&[[1.0, 0.2, 0.3]]));
    sink.end_time_samples();
    sink.attribute(
        AttrDecl::new("int[]", "primvars:skel:jointIndices"),
        Some(Data::Ints(&[0, 1, 2])),
        &[
            Field::new("elementSize", 3.0.into()),
            Field::new("interpolation", "vertex".into()),
        ],
    );
    sink.attribute(
        AttrDecl::new("half3[]", "scales"),
        Some(Data::Float3s(&[[1.2, 1.0, 1.0]])),
        &[],
    );
    sink.attribute(AttrDecl::new("float", "outputs:a"), None, &[]);
    sink.connection(
        AttrDecl::new("token", "outputs:surface"),
        "/Root/M.outputs:a",
    );
    sink.relationship("skel:skeleton", Targets::One("/Root/Skel"));
    sink.relationship(
        "skel:blendShapeTargets",
        Targets::List(&["/Root/M/A".into()]),
    );
    sink.end_prim();
    sink.begin_variant_set("clip");
    sink.begin_variant(
        "walk",
        &[Field::new(
            "customData",
            Value::Dict(vec![("endTimeCode".into(), 5.0.into())]),
        )],
    );
    sink.begin_prim(Specifier::Over, None, "Skel", &[]);
    sink.relationship("skel:animationSource", Targets::One("/Root/A/walk"));
    sink.end_prim();
    sink.end_variant();
    sink.begin_variant("run", &[]);
    sink.end_variant();
    sink.end_variant_set();
    sink.end_prim();
}

/// Line numbers of a read layer's specs set to 0, as a built layer has them.
fn without_lines(mut layer: Layer) -> Layer {
    fn body(b: &mut PrimBody) {
        for p in &mut b.props {
            p.line = 0;
            p.column = 0;
            p.meta.iter_mut().for_each(|m| m.line = 0);
        }
        b.children.iter_mut().for_each(prim);
        for set in &mut b.variant_sets {
            set.line = 0;
            for (_, meta, v) in &mut set.variants {
                meta.iter_mut().for_each(|m| m.line = 0);
                body(v);
            }
        }
    }
    fn prim(p: &mut PrimSpec) {
        p.line = 0;
        p.meta.iter_mut().for_each(|m| m.line = 0);
        body(&mut p.body);
    }
    layer.meta.iter_mut().for_each(|m| m.line = 0);
    body(&mut layer.root);
    layer
}

#[test]
fn the_built_layer_is_the_printed_text_parsed() {
    let mut printer = UsdaPrinter::new(String::new());
    stage(&mut printer);
    let text = printer.into_inner();
    let mut builder = LayerBuilder::default();
    stage(&mut builder);
    let built = builder.finish();
    let parsed = without_lines(parse(&text, Path::new("s.usda")).unwrap());
    assert_eq!(built, parsed, "{text}");
    // The half attribute is narrowed as the parser narrows it.
    let PropKind::Attr {
        default: Some(Value::List(items)),
        ..
    } = &built.root.children[0].body.children[0].body.props[3].kind
    else {
        panic!("scales");
    };
    assert_eq!(
        items[0],
        Value::Tuple(vec![
            Value::Number(1.2001953125),
            Value::Number(1.0),
            Value::Number(1.0)
        ])
    );
}

#[test]
fn unbalanced_calls_are_closed_by_finish() {
    let mut b = LayerBuilder::default();
    b.begin_prim(Specifier::Def, Some("Xform"), "A", &[]);
    b.begin_prim(Specifier::Def, None, "B", &[]);
    b.begin_time_samples(AttrDecl::new("float", "x"));
    b.time_sample(1.0, Data::Float(0.5));
    b.end_variant();
    let layer = b.finish();
    let a = &layer.root.children[0];
    assert_eq!(a.body.children[0].name, "B");
    assert_eq!(a.body.children[0].body.props[0].name, "x");
}
