//! Choices as types: an enum with an `ALL` list and a `name()` becomes a clap `ValueEnum`
//! whose values are those names, so the command line, the study plans and the panels all
//! parse and print a choice the same way, with no string matching of their own.

/// `impl clap::ValueEnum` for an enum with `ALL` and `name()`, the names as its values.
#[macro_export]
macro_rules! named_choice {
    ($t:ty) => {
        impl clap::ValueEnum for $t {
            fn value_variants<'a>() -> &'a [Self] {
                &<$t>::ALL
            }

            fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
                Some(clap::builder::PossibleValue::new(self.name()))
            }
        }
    };
}

/// Parses a choice by its name (any case), or says which names there are.
pub fn parse<T: clap::ValueEnum>(s: &str, what: &str) -> Result<T, String> {
    T::from_str(s.trim(), true).map_err(|_| {
        let names: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value())
            .map(|p| p.get_name().to_string())
            .collect();
        format!("'{s}' is not {what} ({})", names.join(", "))
    })
}

/// `impl serde::Serialize` and `serde::Deserialize` for an enum with `ALL` and `name()`: a
/// choice is written as its name and read back through [`parse`], so a study plan, a manifest
/// or a report names a method the way the command line does, and a wrong name is refused with
/// the list of right ones.
#[macro_export]
macro_rules! named_serde {
    ($t:ty, $what:expr) => {
        impl serde::Serialize for $t {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(self.name())
            }
        }

        impl<'de> serde::Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let name = <String as serde::Deserialize>::deserialize(d)?;
                $crate::choice::parse(&name, $what).map_err(serde::de::Error::custom)
            }
        }
    };
}
