#!/usr/bin/env python3
"""One concept, one type (issue 27): fails when a concept the model defines is defined again,
or when a library names a command-line flag.

    python3 tools/one_concept.py          check the workspace (exit 1 on a second definition)
    python3 tools/one_concept.py --self-test

Checked in the production Rust code of `crates/*/src` and `src/` (test files and inline
`#[cfg(test)] mod tests` blocks are skipped):
- an `enum` whose variants name a skinning method (Lbs and Dqs), an up axis (Y and Z), an
  influence fit (Truncate and Refit) or an output format (two of Glb, Gltf, Usda, Usdc,
  Usdz, Usd), anywhere but the one definition in `crates/model`;
- the text "clip named" in a string literal anywhere but the one clip lookup
  (`crates/model/src/asset.rs`: `find_clip`, `Asset::clip`, `NoSuchClip`);
- a command-line flag (`--` and a name) in a string literal of a library crate: the
  libraries name no flag; the CLI (`src/`) words their errors with its flags;
- a public item of `crates/pipeline` (a `pub` fn, method, struct, enum, trait, const, type
  or static) whose doc comment holds no example (a ``` block): the crate is the API that the
  CLI, batch and the Python bindings call, and each item shows how (its doctests run in the
  test command).
"""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# concept -> (test on the enum's unit (fieldless) variant names and all its variant names,
# the one file allowed to define it). An enum whose variants carry data (one frame's LBS
# palette or DQS data, a prepared glTF or USD file) holds something else per method or
# format, and is not a second definition.
FORMATS = {"glb", "gltf", "usda", "usdc", "usdz", "usd"}
CONCEPTS = {
    "skinning method": (lambda unit, every: {"lbs", "dqs"} <= unit, "crates/model/src/skin.rs"),
    "up axis": (lambda unit, every: {"y", "z"} <= unit, "crates/model/src/frame.rs"),
    "influence fit": (lambda unit, every: {"truncate", "refit"} <= unit, "crates/model/src/skin.rs"),
    # the formats rigport writes, not an input kind among others (OBJ, BVH, ...)
    "output format": (
        lambda unit, every: len(unit & FORMATS) >= 2 and every <= FORMATS,
        "crates/model/src/format.rs",
    ),
}
CLIP_LOOKUP = "crates/model/src/asset.rs"
# The crate each of whose public items carries a doc example.
EXAMPLES_CRATE = "crates/pipeline/src/"
PUBLIC_ITEM = re.compile(r"^\s*pub (?:unsafe )?(fn|struct|enum|trait|const|type|static)\s+(\w+)")

ENUM = re.compile(r"\benum\s+(\w+)\s*(?:<[^>]*>)?\s*\{")
VARIANT = re.compile(r"^\s*(?:#\[[^\]]*\]\s*)*([A-Z]\w*)\s*([({]?)")
STRING = re.compile(r'"(?:[^"\\]|\\.)*"')
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")


def without_tests(text: str) -> str:
    """`text` without an inline `#[cfg(test)] mod tests { ... }`."""
    m = re.search(r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+\w+\s*\{", text)
    return text[: m.start()] if m else text


def production_text(text: str) -> str:
    """`text` without comments and without an inline `#[cfg(test)] mod tests { ... }`."""
    text = without_tests(text)
    return "\n".join(line.split("//", 1)[0] if not is_in_string(line) else line for line in text.split("\n"))


def is_in_string(line: str) -> bool:
    """Whether a `//` on this line may sit inside a string literal (kept whole then)."""
    i = line.find("//")
    return i >= 0 and line[:i].count('"') % 2 == 1


def enum_bodies(text: str):
    for m in ENUM.finditer(text):
        depth, i = 1, m.end()
        while i < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[i], 0)
            i += 1
        body = text[m.end() : i - 1]
        # variants are the comma-separated items at depth 0 of the body
        items, item, depth = [], [], 0
        for ch in body:
            if ch == "," and depth == 0:
                items.append("".join(item))
                item = []
                continue
            depth += {"{": 1, "(": 1, "[": 1, "}": -1, ")": -1, "]": -1}.get(ch, 0)
            item.append(ch)
        items.append("".join(item))
        unit, every = set(), set()
        for it in items:
            v = VARIANT.match(it)
            if v:
                every.add(v.group(1).lower())
                if not v.group(2):
                    unit.add(v.group(1).lower())
        yield m.group(1), unit, every, text.count("\n", 0, m.start()) + 1


def production_files(root: Path):
    for base in [root / "src", *sorted((root / "crates").glob("*/src"))]:
        for path in sorted(base.rglob("*.rs")):
            rel = path.relative_to(root).as_posix()
            if path.name in ("tests.rs", "test_support.rs") or "/tests/" in rel or rel.startswith("crates/testkit/"):
                continue
            yield rel, path.read_text(encoding="utf-8")


def check(files) -> list[str]:
    problems = []
    for rel, text in files:
        code = production_text(text)
        for name, unit, every, line in enum_bodies(code):
            for concept, (names_it, home) in CONCEPTS.items():
                if names_it(unit, every) and rel != home:
                    problems.append(f"{rel}:{line}: enum {name} names {'an' if concept[0] in 'aeiou' else 'a'} {concept}; use the one in {home}")
        if rel.startswith("crates/"):
            for m in STRING.finditer(code):
                flag = FLAG.search(m.group(0))
                if flag:
                    line = code.count("\n", 0, m.start()) + 1
                    problems.append(f"{rel}:{line}: the library names the flag {flag.group(0)}; the CLI adds flag names")
        if rel != CLIP_LOOKUP:
            for m in STRING.finditer(code):
                if "clip named" in m.group(0):
                    line = code.count("\n", 0, m.start()) + 1
                    problems.append(
                        f"{rel}:{line}: \"clip named\" outside the one clip lookup ({CLIP_LOOKUP}); use Asset::clip / find_clip"
                    )
        if rel.startswith(EXAMPLES_CRATE):
            problems.extend(f"{rel}:{line}: {what}" for line, what in items_without_example(without_tests(text)))
    return problems


def items_without_example(code: str):
    """(line, "pub fn name has no doc example") for each public item whose doc has no ```."""
    lines = code.split("\n")
    for i, text in enumerate(lines):
        m = PUBLIC_ITEM.match(text)
        if not m:
            continue
        j, doc = i - 1, []
        while j >= 0 and lines[j].strip().startswith(("///", "#[")):
            doc.append(lines[j])
            j -= 1
        if not any("```" in d for d in doc):
            yield i + 1, f"pub {m.group(1)} {m.group(2)} has no doc example"


def self_test() -> None:
    bad = [
        ("src/cli.rs", "pub enum Skinning {\n    /// doc\n    Lbs,\n    Dqs,\n}\n"),
        ("crates/render/src/lib.rs", "enum Axis { Y, Z }"),
        ("crates/eval/src/x.rs", "pub enum Fit { Truncate, Refit }"),
        ("crates/export/src/e.rs", "pub(crate) enum Encoding { Usda, Usdc, Usdz }"),
        ("crates/x/src/y.rs", 'fn f() { let m = format!("no clip named {n:?}"); }'),
        ("crates/pipeline/src/z.rs", 'const HINT: &str = "raise it with --max-memory";'),
        ("crates/pipeline/src/w.rs", "/// Does it.\n#[must_use]\npub fn run() {}\n"),
    ]
    assert len(check(bad)) == 7, check(bad)
    good = [
        ("crates/model/src/skin.rs", "pub enum SkinningMethod { Lbs, Dqs }"),
        ("crates/render/src/lib.rs", "pub enum View { Front, Side }"),
        ("crates/eval/src/f.rs", "enum Kind<'a> { Lbs(&'a [Mat4]), Dqs(Frame<'a>) }"),
        ("crates/import/src/detect.rs", "pub enum Kind { Obj, Bvh, Gltf, Usda }"),
        ("crates/x/src/y.rs", "// no clip named here\n#[cfg(test)]\nmod tests { enum S { Lbs, Dqs } }"),
        ("crates/model/src/asset.rs", '#[error("no clip named {name:?}")]'),
        ("src/exit.rs", 'const HINT: &str = "raise it with --max-memory";'),
        ("crates/x/src/y.rs", 'let a = "x -- y"; let b = "a--b";'),
        ("crates/pipeline/src/w.rs", "/// Does it.\n///\n/// ```\n/// run();\n/// ```\npub fn run() {}\npub(crate) fn f() {}\n"),
    ]
    assert check(good) == [], check(good)
    print("one_concept self-test: ok")


def main() -> int:
    if sys.argv[1:] == ["--self-test"]:
        self_test()
        return 0
    problems = check(production_files(ROOT))
    for p in problems:
        print(p, file=sys.stderr)
    if problems:
        print(f"one_concept: {len(problems)} problem(s)", file=sys.stderr)
        return 1
    print("one_concept: each concept is defined once; the libraries name no flag; every public item of the pipeline crate has an example")
    return 0


if __name__ == "__main__":
    sys.exit(main())
