//! Layer metadata (`upAxis`, `metersPerUnit`, `timeCodesPerSecond`/`framesPerSecond`)
//! and the warnings for composition arcs (references, payloads, ...) that are not resolved.

use rigport_model::{UpAxis, Warning};

use super::importer::Importer;
use super::layer;
use super::stage;
use super::values::{number, token};
use crate::problem::Rule;
use crate::{ImportError, Location};

/// USD's fallback `metersPerUnit` when a stage does not author it (centimetres,
/// `UsdGeomLinearUnits` / `UsdGeomGetStageMetersPerUnit`).
pub const DEFAULT_METERS_PER_UNIT: f64 = 0.01;

/// USD's fallback `timeCodesPerSecond` (`SdfSchema`, 24).
pub const DEFAULT_TIME_CODES_PER_SECOND: f64 = 24.0;

impl<'l> Importer<'l, '_> {
    fn layer_meta(&self, key: &str) -> Option<&'l layer::Meta> {
        self.layer.meta.iter().rev().find(|m| m.key == key)
    }

    pub(super) fn layer_metadata(&mut self) -> Result<(), ImportError> {
        let rate = |key: &'static str| -> Result<Option<f64>, ImportError> {
            let Some(m) = self.layer_meta(key) else {
                return Ok(None);
            };
            match number(&m.value) {
                Some(n) if n.is_finite() && n > 0.0 => Ok(Some(n)),
                _ => Err(ImportError::at(
                    Location::line(self.path, m.line),
                    Rule::NotPositive(key),
                )),
            }
        };
        // UsdStage::GetTimeCodesPerSecond: the layer's timeCodesPerSecond, else its
        // framesPerSecond, else 24.
        self.tcps = match (rate("timeCodesPerSecond")?, rate("framesPerSecond")?) {
            (Some(t), _) | (None, Some(t)) => t,
            (None, None) => DEFAULT_TIME_CODES_PER_SECOND,
        };
        if let Some(m) = self.layer_meta("upAxis") {
            match token(&m.value) {
                Some("Y") => self.up_axis = UpAxis::Y,
                Some("Z") => self.up_axis = UpAxis::Z,
                _ => {
                    return Err(ImportError::at(
                        Location::line(self.path, m.line),
                        Rule::UpAxis,
                    ))
                }
            }
        }
        if let Some(m) = self.layer_meta("subLayers") {
            let n = stage::list_items(&m.value).len();
            if n > 0 {
                self.warnings.push(Warning::Incomplete {
                    location: Location::line(self.path, m.line).to_string(),
                    message: format!(
                        "{n} sublayer(s) not read: rigport reads a single .usda layer"
                    ),
                });
            }
        }
        Ok(())
    }

    pub(super) fn meters_per_unit(&self) -> Result<f64, ImportError> {
        match self.layer_meta("metersPerUnit") {
            None => Ok(DEFAULT_METERS_PER_UNIT),
            Some(m) => match number(&m.value) {
                Some(n) if n.is_finite() && n > 0.0 => Ok(n),
                _ => Err(ImportError::at(
                    Location::line(self.path, m.line),
                    Rule::NotPositive("metersPerUnit"),
                )),
            },
        }
    }

    /// Notes for unresolved arcs and properties written twice.
    pub(super) fn composition_warnings(&mut self) {
        let mut notes = Vec::new();
        for (i, prim) in self.stage.prims.iter().enumerate() {
            if !self.stage.in_scene(i) && prim.defined {
                continue;
            }
            if !prim.arcs.is_empty() {
                notes.push((
                    prim.path.clone(),
                    true,
                    format!(
                        "{} not resolved (rigport reads a single .usda layer): what they bring \
                         is missing",
                        prim.arcs.join(", ")
                    ),
                ));
            }
            for (name, prop) in &prim.props {
                if prop.rewritten > 0 {
                    notes.push((
                        prim.path.clone(),
                        false,
                        format!(
                            "{name} is written {} times; the last statement (line {}) wins",
                            prop.rewritten + 1,
                            prop.line
                        ),
                    ));
                }
            }
        }
        for (path, incomplete, message) in notes {
            if incomplete {
                self.incomplete(&path, message);
            } else {
                self.note(&path, message);
            }
        }
    }
}
