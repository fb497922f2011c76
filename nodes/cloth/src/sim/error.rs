//! Why a cloth simulation cannot start or go on, in the simulation's terms: the parameter at
//! fault and why. The node turns it into an error on that port.

use pyrograph_core::declare::AnimError;

/// Why a cloth simulation cannot start or go on: the parameter at fault (its port) and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("port '{param}': {message}")]
pub struct ClothError {
    /// The parameter's name.
    pub param: String,
    /// What is wrong.
    pub message: String,
}

impl ClothError {
    /// An error about parameter `param`.
    pub fn new(param: impl Into<String>, message: impl Into<String>) -> Self {
        ClothError { param: param.into(), message: message.into() }
    }
}

impl From<AnimError> for ClothError {
    fn from(e: AnimError) -> Self {
        ClothError { param: e.port, message: e.message }
    }
}
