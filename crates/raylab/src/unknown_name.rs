//! The error of every option parsed from its name (integrators, AOVs, filters, tone maps, light
//! sampling, instancing): which kind of option, the name given, and the names there are.

/// A name that no option of its kind has.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} '{name}': expected {expected}")]
pub struct UnknownName {
    /// The kind of option: `"integrator"`, `"filter"`, ….
    pub what: &'static str,
    /// The name given.
    pub name: String,
    /// The names there are, as a phrase: `"box or gaussian"`.
    pub expected: &'static str,
}

impl UnknownName {
    /// The error for `name`, an unknown `what`.
    pub fn new(what: &'static str, name: &str, expected: &'static str) -> UnknownName {
        UnknownName { what, name: name.to_owned(), expected }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_says_what_was_given_and_what_there_is() {
        let error = UnknownName::new("filter", "tent", "box or gaussian");
        assert_eq!(error.to_string(), "unknown filter 'tent': expected box or gaussian");
    }
}
