//! What a check that fails returns: the rule of spec section 11 it breaks, and the detail.

use std::fmt;

/// A file that breaks a rule of spec/FORMAT.md section 11. `rule` is the rule's id (such as
/// `"R39-traversal"`) and `detail` says what is wrong, in the words of the Python reference, so
/// that both give the same message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Broken {
    pub rule: &'static str,
    pub detail: String,
}

impl Broken {
    pub fn new(rule: &'static str, detail: impl Into<String>) -> Self {
        Broken {
            rule,
            detail: detail.into(),
        }
    }
}

impl fmt::Display for Broken {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.rule, self.detail)
    }
}

impl std::error::Error for Broken {}
