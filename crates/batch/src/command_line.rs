//! An item as the command line a CLI runs in-process: `rigport COMMAND INPUTS... OPTIONS...
//! -o OUTPUT`, for the commands the caller allows, and the error of one that does not
//! parse.

use std::ffi::OsString;
use std::path::PathBuf;

use crate::{FailureKind, Item, ItemError};

/// `program COMMAND INPUTS... OPTIONS... -o OUTPUT` for `item`, whose command must be one
/// of `commands` and which must write exactly one of `outputs`.
///
/// ```
/// use rigport_batch::{command_line::argv, Item};
/// let item = Item { command: "convert".into(), inputs: vec!["walk.bvh".into()], ..Item::default() };
/// let line = argv("rigport", &item, &["convert"], &["out/walk.glb".into()]).expect("allowed");
/// assert_eq!(line, ["rigport", "convert", "walk.bvh", "-o", "out/walk.glb"]);
/// assert!(argv("rigport", &item, &["eval"], &["a.npz".into()]).is_err());
/// ```
///
/// # Errors
/// Another command, or not one output (input failures: retrying cannot help).
pub fn argv(
    program: &str,
    item: &Item,
    commands: &[&str],
    outputs: &[PathBuf],
) -> Result<Vec<OsString>, ItemError> {
    if !commands.contains(&item.command.as_str()) {
        let expected = commands.join(", ");
        return Err(input(format!(
            "command {:?} cannot run in a batch; expected one of {expected}",
            item.command
        )));
    }
    let [output] = outputs else {
        return Err(input(format!("{} writes one output", item.command)));
    };
    Ok(item.command_line(program, output))
}

/// The failure of an item whose command line does not parse: the parser's first line,
/// after the command's name.
///
/// ```
/// use rigport_batch::{command_line::unparsed, Item};
/// let item = Item { command: "convert".into(), ..Item::default() };
/// let e = unparsed(&item, "error: unexpected argument '--x' found\n\nUsage: ...");
/// assert_eq!(e.message, "convert: unexpected argument '--x' found");
/// ```
pub fn unparsed(item: &Item, parser_message: &str) -> ItemError {
    let first = parser_message.lines().next().unwrap_or_default();
    input(format!(
        "{}: {}",
        item.command,
        first.trim_start_matches("error: ")
    ))
}

/// An input failure.
fn input(message: String) -> ItemError {
    ItemError {
        kind: FailureKind::Input,
        message,
    }
}
