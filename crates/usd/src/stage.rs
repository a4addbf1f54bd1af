//! A single `.usda` layer composed into prims: variant selections applied, repeated
//! property statements merged, paths assigned, relationship targets resolved.
//!
//! This is the part of USD composition (LIVRPS strength order, "Local" then "Variants")
//! that one layer needs. References, payloads, inherits, specializes and sublayers name
//! other layers or prims whose opinions rigport does not read; the prims that carry them
//! are recorded in [`Prim::arcs`] so the importer can warn or fail.

use std::collections::HashMap;

use super::layer::{ListOp, Meta, PrimBody, PrimSpec, PropKind, PropSpec, Specifier, Value};

/// A composed property.
#[derive(Clone, Debug, Default)]
pub struct Prop<'l> {
    /// Value type for attributes (`point3f[]`); `None` for relationships.
    pub type_name: Option<&'l str>,
    /// The default value (`Value::None` when blocked).
    pub default: Option<&'l Value>,
    /// Time samples, sorted by time, later statements winning on equal times.
    pub samples: Option<Vec<(f64, &'l Value)>>,
    /// Relationship targets as written.
    pub targets: Option<&'l [String]>,
    /// Attribute connection targets as written (`.connect`).
    pub connect: Option<&'l [String]>,
    /// Metadata, strongest first.
    pub meta: Vec<&'l Meta>,
    /// 1-based line of the strongest statement.
    pub line: usize,
    /// How many statements of the same layer site wrote the same field again (the last
    /// one wins, as `Sdf` reads a layer).
    pub rewritten: usize,
}

impl<'l> Prop<'l> {
    /// A metadata value, strongest opinion.
    pub fn meta(&self, key: &str) -> Option<&'l Value> {
        self.meta.iter().find(|m| m.key == key).map(|m| &m.value)
    }
}

/// A composed prim.
#[derive(Clone, Debug)]
pub struct Prim<'l> {
    /// Absolute path (`/Root/Skel`).
    pub path: String,
    /// The prim name.
    pub name: &'l str,
    /// The schema type, strongest opinion.
    pub type_name: Option<&'l str>,
    /// Whether some spec is `def` (a prim that only has `over`s is not defined).
    pub defined: bool,
    /// Whether a spec is `class` (abstract) or `active = false`.
    pub inactive_or_abstract: bool,
    /// Applied API schemas (`apiSchemas` list op, every op but `delete` counted).
    pub api_schemas: Vec<&'l str>,
    /// Properties by name, in first-written order.
    pub props: Vec<(&'l str, Prop<'l>)>,
    /// Child prim indices into [`Stage::prims`].
    pub children: Vec<usize>,
    /// Parent index; `None` for root prims.
    pub parent: Option<usize>,
    /// Composition arcs that are not resolved (`references`, `payload`, `inherits`,
    /// `specializes`) authored on this prim.
    pub arcs: Vec<&'l str>,
    /// The variant selections in force on this prim (set, variant).
    pub selections: Vec<(&'l str, &'l str)>,
    /// Its variant sets: name and variant names.
    pub variant_sets: Vec<(&'l str, Vec<&'l str>)>,
}

impl<'l> Prim<'l> {
    /// A property by name.
    pub fn prop(&self, name: &str) -> Option<&Prop<'l>> {
        self.props.iter().find(|(n, _)| *n == name).map(|(_, p)| p)
    }

    /// Whether the prim is part of the scene (defined, active, not abstract).
    pub fn is_scene_prim(&self) -> bool {
        self.defined && !self.inactive_or_abstract
    }
}

/// The composed prims of one layer.
#[derive(Clone, Debug, Default)]
pub struct Stage<'l> {
    /// Every prim, parents before children, in namespace (document) order.
    pub prims: Vec<Prim<'l>>,
    /// Root prim indices.
    pub roots: Vec<usize>,
    by_path: HashMap<String, usize>,
}

/// A variant selection to impose instead of the authored one: (prim path, set, variant).
pub type Override<'a> = (&'a str, &'a str, &'a str);

impl<'l> Stage<'l> {
    /// Composes the root prims of a layer; `force` replaces one prim's selection in one
    /// variant set (used to read the variants that are not selected).
    pub fn compose(root: &'l PrimBody, force: Option<Override<'_>>) -> Self {
        let mut stage = Stage::default();
        let specs: Vec<&PrimSpec> = root.children.iter().collect();
        for group in group_by_name(&[&specs]) {
            let idx = stage.add_prim(&group, None, "", force);
            stage.roots.push(idx);
        }
        stage
    }

    /// The prim at an absolute path.
    pub fn get(&self, path: &str) -> Option<&Prim<'l>> {
        self.by_path.get(path).and_then(|&i| self.prims.get(i))
    }

    /// The index of the prim at an absolute path.
    pub fn index(&self, path: &str) -> Option<usize> {
        self.by_path.get(path).copied()
    }

    /// Whether the prim and all its ancestors are scene prims (USD's default traversal
    /// prunes a subtree at an undefined, inactive or abstract prim).
    pub fn in_scene(&self, index: usize) -> bool {
        let mut cur = Some(index);
        while let Some(i) = cur {
            let Some(p) = self.prims.get(i) else {
                return false;
            };
            if !p.is_scene_prim() {
                return false;
            }
            cur = p.parent;
        }
        true
    }

    /// The prim and its ancestors, nearest first.
    pub fn ancestry(&self, index: usize) -> impl Iterator<Item = &Prim<'l>> + '_ {
        let mut cur = Some(index);
        std::iter::from_fn(move || {
            let p = self.prims.get(cur?)?;
            cur = p.parent;
            Some(p)
        })
    }

    /// Composes one prim from its specs, strongest first. Returns its index.
    fn add_prim(
        &mut self,
        specs: &[&'l PrimSpec],
        parent: Option<usize>,
        parent_path: &str,
        force: Option<Override<'_>>,
    ) -> usize {
        let name = specs.first().map_or("", |s| s.name.as_str());
        let path = format!("{parent_path}/{name}");
        // Gather every body in strength order: each spec's own body, then the bodies of
        // the variants selected on it (recursively: a variant may select further ones).
        let mut metas: Vec<&'l Meta> = Vec::new();
        for s in specs {
            metas.extend(s.meta.iter());
        }
        let mut bodies: Vec<&'l PrimBody> = specs.iter().map(|s| &s.body).collect();
        let mut selections: Vec<(&'l str, &'l str)> = Vec::new();
        let mut variant_sets: Vec<(&'l str, Vec<&'l str>)> = Vec::new();
        let mut k = 0;
        while let Some(body) = bodies.get(k).copied() {
            k += 1;
            for set in &body.variant_sets {
                if !variant_sets.iter().any(|(n, _)| *n == set.name) {
                    variant_sets.push((
                        &set.name,
                        set.variants.iter().map(|(v, _, _)| v.as_str()).collect(),
                    ));
                }
                let chosen = match force {
                    Some((p, s, v)) if p == path && s == set.name => Some(v),
                    _ => selection(&metas, &set.name),
                };
                let Some(chosen) = chosen else { continue };
                if let Some((vname, vmeta, vbody)) =
                    set.variants.iter().find(|(v, _, _)| v == chosen)
                {
                    if !selections.iter().any(|(s, _)| *s == set.name) {
                        selections.push((&set.name, vname));
                    }
                    metas.extend(vmeta.iter());
                    // Guard against a body listed twice (it cannot nest into itself, but
                    // two sets could select the same body object only by aliasing).
                    if bodies.len() < 10_000 {
                        bodies.push(vbody);
                    }
                }
            }
        }
        let type_name = specs.iter().find_map(|s| s.type_name.as_deref());
        let defined = specs.iter().any(|s| s.specifier == Specifier::Def);
        let abstract_ = specs.iter().any(|s| s.specifier == Specifier::Class);
        let inactive = metas.iter().find(|m| m.key == "active").is_some_and(|m| {
            matches!(&m.value, Value::Ident(v) if v == "false" || v == "0")
                || m.value == Value::Number(0.0)
        });
        let mut api_schemas = Vec::new();
        for m in metas.iter().filter(|m| m.key == "apiSchemas") {
            if m.op == ListOp::Delete {
                continue;
            }
            for v in list_items(&m.value) {
                if let Value::Str(s) | Value::Ident(s) = v {
                    if !api_schemas.contains(&s.as_str()) {
                        api_schemas.push(s.as_str());
                    }
                }
            }
        }
        let mut arcs = Vec::new();
        for m in &metas {
            let arc = match m.key.as_str() {
                "references" => "references",
                "payload" => "payload",
                "inherits" => "inherits",
                "specializes" => "specializes",
                _ => continue,
            };
            if m.op != ListOp::Delete && m.value != Value::None && !arcs.contains(&arc) {
                arcs.push(arc);
            }
        }
        let mut props: Vec<(&'l str, Prop<'l>)> = Vec::new();
        for body in &bodies {
            let mut site: Vec<(&'l str, Prop<'l>)> = Vec::new();
            for spec in &body.props {
                merge_statement(&mut site, spec);
            }
            for (name, prop) in site {
                match props.iter_mut().find(|(n, _)| *n == name) {
                    // A stronger site already has the property: it keeps the fields it
                    // authored, the weaker site fills the rest.
                    Some((_, strong)) => fill_weaker(strong, prop),
                    None => props.push((name, prop)),
                }
            }
        }
        let index = self.prims.len();
        self.prims.push(Prim {
            path: path.clone(),
            name,
            type_name,
            defined,
            inactive_or_abstract: abstract_ || inactive,
            api_schemas,
            props,
            children: Vec::new(),
            parent,
            arcs,
            selections,
            variant_sets,
        });
        self.by_path.entry(path.clone()).or_insert(index);
        let child_lists: Vec<Vec<&'l PrimSpec>> =
            bodies.iter().map(|b| b.children.iter().collect()).collect();
        let refs: Vec<&[&'l PrimSpec]> = child_lists.iter().map(Vec::as_slice).collect();
        let mut children = Vec::new();
        for group in group_by_name(&refs) {
            children.push(self.add_prim(&group, Some(index), &path, force));
        }
        if let Some(p) = self.prims.get_mut(index) {
            p.children = children;
        }
        index
    }
}

/// The selection of variant set `set` in prim metadata `variants = { string set = "v" }`,
/// strongest first.
fn selection<'l>(metas: &[&'l Meta], set: &str) -> Option<&'l str> {
    metas.iter().find_map(|m| {
        if m.key != "variants" {
            return None;
        }
        let Value::Dict(entries) = &m.value else {
            return None;
        };
        entries.iter().find_map(|(k, v)| match v {
            Value::Str(s) | Value::Ident(s) if k == set => Some(s.as_str()),
            _ => None,
        })
    })
}

/// The items of a list value, or the value itself when it is a single item.
pub fn list_items(value: &Value) -> &[Value] {
    match value {
        Value::List(items) => items,
        Value::None => &[],
        other => std::slice::from_ref(other),
    }
}

/// Children of several bodies (strongest first) grouped by name: each group lists the
/// specs of one child, strongest first; groups in first-seen order.
fn group_by_name<'l>(lists: &[&[&'l PrimSpec]]) -> Vec<Vec<&'l PrimSpec>> {
    let mut groups: Vec<Vec<&'l PrimSpec>> = Vec::new();
    let mut at: HashMap<&'l str, usize> = HashMap::new();
    for list in lists {
        for spec in list.iter().copied() {
            match at.get(spec.name.as_str()) {
                Some(&g) => {
                    if let Some(group) = groups.get_mut(g) {
                        group.push(spec);
                    }
                }
                None => {
                    at.insert(&spec.name, groups.len());
                    groups.push(vec![spec]);
                }
            }
        }
    }
    groups
}

/// Adds one property statement to the properties of one layer site: a later statement
/// of the same field replaces the earlier one, as `Sdf` does when it reads a layer.
fn merge_statement<'l>(site: &mut Vec<(&'l str, Prop<'l>)>, spec: &'l PropSpec) {
    let idx = match site.iter().position(|(n, _)| *n == spec.name) {
        Some(i) => i,
        None => {
            site.push((
                &spec.name,
                Prop {
                    line: spec.line,
                    ..Prop::default()
                },
            ));
            site.len() - 1
        }
    };
    let Some((_, prop)) = site.get_mut(idx) else {
        return;
    };
    match &spec.kind {
        PropKind::Attr {
            type_name,
            default,
            samples,
            connect,
            ..
        } => {
            prop.type_name = Some(type_name);
            if let Some(c) = connect {
                prop.connect = Some(c);
            }
            if let Some(d) = default {
                if prop.default.is_some() {
                    prop.rewritten += 1;
                }
                prop.default = Some(d);
                prop.line = spec.line;
            }
            if let Some(s) = samples {
                if prop.samples.is_some() {
                    prop.rewritten += 1;
                }
                prop.samples = Some(sorted_samples(s));
                prop.line = spec.line;
            }
        }
        PropKind::Rel { targets } => {
            if let Some(t) = targets {
                if prop.targets.is_some() {
                    prop.rewritten += 1;
                }
                prop.targets = Some(t);
                prop.line = spec.line;
            }
        }
    }
    // Later metadata of the same site wins: put it first.
    let mut meta: Vec<&'l Meta> = spec.meta.iter().collect();
    meta.append(&mut prop.meta);
    prop.meta = meta;
}

/// Samples sorted by time; of equal times the later statement wins.
fn sorted_samples(samples: &[(f64, Value)]) -> Vec<(f64, &Value)> {
    let mut out: Vec<(f64, &Value)> = Vec::with_capacity(samples.len());
    for (t, v) in samples {
        match out.iter_mut().rev().find(|(u, _)| u == t) {
            Some(slot) => slot.1 = v,
            None => out.push((*t, v)),
        }
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// Fills the fields a stronger site left unauthored from a weaker one.
fn fill_weaker<'l>(strong: &mut Prop<'l>, weak: Prop<'l>) {
    // Value resolution: the strongest site with any value (samples or default) decides;
    // within that site samples beat the default.
    let strong_has_value = strong.default.is_some() || strong.samples.is_some();
    if !strong_has_value {
        strong.default = weak.default;
        strong.samples = weak.samples;
    }
    if strong.type_name.is_none() {
        strong.type_name = weak.type_name;
    }
    if strong.connect.is_none() {
        strong.connect = weak.connect;
    }
    if strong.targets.is_none() {
        strong.targets = weak.targets;
    }
    strong.meta.extend(weak.meta);
}

#[cfg(test)]
mod tests {
    use super::super::parse::parse;
    use super::*;
    use std::path::Path;

    const TEXT: &str = r#"#usda 1.0
def Xform "A" (
    variants = { string v = "two" }
    prepend variantSets = "v"
)
{
    float x = 1
    float x = 2
    float y.timeSamples = { 2: 20, 1: 10, 2: 21 }
    variantSet "v" = {
        "one" { float z = 1 def "OnlyOne" {} }
        "two" { float x = 99  float z = 2  def "B" { float w = 3 } }
    }
    def "B" { float q = 4 }
    over "C" { def Mesh "D" {} }
    class "K" {}
}
"#;

    #[test]
    fn composes_local_over_selected_variant() {
        let layer = parse(TEXT, Path::new("t.usda")).unwrap();
        let stage = Stage::compose(&layer.root, None);
        let a = stage.get("/A").unwrap();
        assert_eq!(a.selections, vec![("v", "two")]);
        let x = a.prop("x").unwrap();
        assert_eq!(
            x.default,
            Some(&Value::Number(2.0)),
            "local beats the variant"
        );
        assert_eq!(x.rewritten, 1);
        assert_eq!(a.prop("z").unwrap().default, Some(&Value::Number(2.0)));
        let y = a.prop("y").unwrap().samples.clone().unwrap();
        assert_eq!(
            y,
            vec![(1.0, &Value::Number(10.0)), (2.0, &Value::Number(21.0))]
        );
        let b = stage.get("/A/B").unwrap();
        assert!(b.prop("q").is_some() && b.prop("w").is_some());
        assert!(stage.get("/A/OnlyOne").is_none());
        let d = stage.index("/A/C/D").unwrap();
        assert!(!stage.in_scene(d), "under an over without def");
        assert!(!stage.in_scene(stage.index("/A/K").unwrap()));
        let forced = Stage::compose(&layer.root, Some(("/A", "v", "one")));
        assert!(forced.get("/A/OnlyOne").is_some());
        assert_eq!(
            forced.get("/A").unwrap().prop("z").unwrap().default,
            Some(&Value::Number(1.0))
        );
    }
}
