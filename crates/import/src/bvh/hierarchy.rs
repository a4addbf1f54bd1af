//! The `HIERARCHY` section: `ROOT` and `JOINT` blocks, `OFFSET`, `CHANNELS`, `End Site`.

use glam::Vec3;
use rigport_model::Warning;

use crate::problem::{Mismatch, Missing, Repeated};
use crate::{ImportError, Location, Problem};

use super::parser::{keyword, Parser};
use super::types::{BvhEndSite, BvhJoint, Channel};
use crate::text::Token;

impl<'a> Parser<'a, '_> {
    /// `OFFSET x y z` with nothing after it on the line.
    fn offset(&mut self) -> Result<Vec3, ImportError> {
        let kw = self.expect("OFFSET")?;
        if !keyword(kw, "OFFSET") {
            return Err(self.syntax(kw, "OFFSET"));
        }
        let mut xyz = [0.0_f32; 3];
        for v in &mut xyz {
            let t = self.expect_on_line(kw, "3 numbers")?;
            *v = self.number(t, "OFFSET value")?;
        }
        if let Some(t) = self.next_on_line() {
            return Err(self.syntax(t, "the end of the line after OFFSET's 3 numbers"));
        }
        Ok(Vec3::from_array(xyz))
    }

    /// `{`, unless it ended the previous line (`brace_seen`).
    fn open_brace(&mut self, brace_seen: bool) -> Result<(), ImportError> {
        if brace_seen {
            return Ok(());
        }
        let t = self.expect("{")?;
        if t.text == "{" {
            Ok(())
        } else {
            Err(self.syntax(t, "{"))
        }
    }

    /// A `ROOT` block and everything in it, `root` being the `ROOT` token. Iterative, so
    /// deep nesting cannot overflow the stack.
    pub(super) fn hierarchy(&mut self, root: Token<'a>) -> Result<(), ImportError> {
        let mut open = vec![self.joint(root, None)?];
        while let Some(&j) = open.last() {
            let t = self.next().ok_or_else(|| {
                let (name, line) = self
                    .joints
                    .get(j)
                    .map_or(("", 0), |j| (j.name.as_str(), j.line));
                ImportError::new(
                    Location::line(self.path, self.last_line),
                    Problem::Truncated(format!(
                        "the file ends inside joint {name:?} (line {line}): expected JOINT, End Site or }}"
                    )),
                )
            })?;
            if keyword(t, "JOINT") {
                open.push(self.joint(t, Some(j))?);
            } else if keyword(t, "End") {
                self.end_site(t, j)?;
            } else if t.text == "}" {
                open.pop();
            } else {
                return Err(self.syntax(t, "JOINT, End Site or }"));
            }
        }
        Ok(())
    }

    /// A joint's header: name, `{`, `OFFSET`, optional `CHANNELS`. Returns its index.
    fn joint(&mut self, kw: Token<'a>, parent: Option<usize>) -> Result<usize, ImportError> {
        let mut words = Vec::new();
        while let Some(t) = self.next_on_line() {
            words.push(t);
        }
        let brace_seen = words.last().is_some_and(|t| t.text == "{");
        if brace_seen {
            words.pop();
        }
        if words.is_empty() {
            return Err(ImportError::at(
                self.at(kw),
                Missing::JointName(kw.text.to_string()),
            ));
        }
        let name = words.iter().map(|t| t.text).collect::<Vec<_>>().join("_");
        if words.len() > 1 {
            let written = words.iter().map(|t| t.text).collect::<Vec<_>>().join(" ");
            self.warnings.push(Warning::Repaired {
                location: format!("{}:{}", self.path.display(), kw.line),
                message: format!(
                    "joint name {written:?} has several words: named {name:?} (as Blender does)"
                ),
            });
        }
        self.open_brace(brace_seen)?;
        let offset = self.offset()?;
        let mut channels = Vec::new();
        let mut peek = self.cur;
        if let Some(t) = peek.next_token().filter(|t| keyword(*t, "CHANNELS")) {
            self.cur = peek;
            self.last_line = t.line;
            channels = self.channels(t)?;
        }
        let index = self.joints.len();
        self.joints.push(BvhJoint {
            name,
            parent,
            offset,
            first_channel: self.channel_total,
            line: kw.line,
            channels,
        });
        self.channel_total += self.joints.last().map_or(0, |j| j.channels.len());
        Ok(index)
    }

    /// The rest of a `CHANNELS n name...` line, `kw` being `CHANNELS`.
    fn channels(&mut self, kw: Token<'a>) -> Result<Vec<Channel>, ImportError> {
        let count_token = self.expect_on_line(kw, "a channel count")?;
        let count: usize =
            crate::text::number(count_token.text, "channel count", || self.at(count_token))?;
        if count > Channel::ALL.len() {
            return Err(ImportError::at(
                self.at(count_token),
                Mismatch::Channels(count),
            ));
        }
        let mut channels: Vec<Channel> = Vec::with_capacity(count);
        while channels.len() < count {
            let Some(t) = self.next_on_line() else {
                return Err(ImportError::at(
                    self.at(kw),
                    Mismatch::ChannelNames {
                        count,
                        names: channels.len(),
                    },
                ));
            };
            let c = Channel::parse(t.text).ok_or_else(|| {
                self.syntax(
                    t,
                    "a channel name (Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation)",
                )
            })?;
            if channels.contains(&c) {
                return Err(ImportError::at(self.at(t), Repeated::Channel(c.name())));
            }
            channels.push(c);
        }
        if let Some(t) = self.next_on_line() {
            return Err(if Channel::parse(t.text).is_some() {
                ImportError::at(self.at(t), Mismatch::MoreChannelNames(count))
            } else {
                self.syntax(t, "the end of the line after the channel names")
            });
        }
        Ok(channels)
    }

    /// An `End Site` block inside joint `parent`, `kw` being `End`.
    fn end_site(&mut self, kw: Token<'a>, parent: usize) -> Result<(), ImportError> {
        let site = self.expect_on_line(kw, "Site")?;
        if !keyword(site, "Site") {
            return Err(self.syntax(site, "Site"));
        }
        let brace_seen = match self.next_on_line() {
            None => false,
            Some(t) if t.text == "{" => true,
            Some(t) => return Err(self.syntax(t, "the end of the line after End Site")),
        };
        self.open_brace(brace_seen)?;
        let offset = self.offset()?;
        let close = self.expect("}")?;
        if close.text != "}" {
            return Err(self.syntax(close, "}"));
        }
        self.end_sites.push(BvhEndSite {
            parent,
            offset,
            line: kw.line,
        });
        Ok(())
    }
}
