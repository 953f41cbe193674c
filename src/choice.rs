//! Choices as types: an enum with an `ALL` list and a `name()` (written once by `choice!`)
//! becomes a clap `ValueEnum` whose values are those names, so the command line, the study
//! plans and the panels all parse and print a choice the same way, with no string matching of
//! their own.

/// Choices as types, written once. Three forms:
///
/// - `choice! { enum … { Variant => "name", … } }` defines the enum (attributes and docs kept)
///   with `ALL` (its variants in order), `name()`, `Display` by that name and a clap
///   `ValueEnum` whose values are the names;
/// - `choice! { own_values; enum … }` the same without the `ValueEnum`, for an enum that
///   derives its own (with each variant's doc as help) or parses names its own way;
/// - `choice!(Type)` the `Display` and `ValueEnum` of an enum that writes `ALL` and `name()`
///   itself (one whose variants carry data).
#[macro_export]
macro_rules! choice {
    (
        own_values;
        $(#[$meta:meta])*
        $vis:vis enum $name:ident {
            $( $(#[$vmeta:meta])* $variant:ident => $text:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        $vis enum $name {
            $( $(#[$vmeta])* $variant ),+
        }

        impl $name {
            /// Every choice, in the order they are declared (and offered).
            pub const ALL: [$name; [$(stringify!($variant)),+].len()] = [$($name::$variant),+];

            /// The name the command line, the panels and the reports use.
            pub fn name(self) -> &'static str {
                match self {
                    $( $name::$variant => $text ),+
                }
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident { $($body:tt)* }
    ) => {
        $crate::choice! { own_values; $(#[$meta])* $vis enum $name { $($body)* } }
        $crate::choice!(@values $name);
    };
    (@values $t:ty) => {
        impl clap::ValueEnum for $t {
            fn value_variants<'a>() -> &'a [Self] {
                &<$t>::ALL
            }

            fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
                Some(clap::builder::PossibleValue::new(self.name()))
            }
        }
    };
    ($t:ty) => {
        impl std::fmt::Display for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        $crate::choice!(@values $t);
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

#[cfg(test)]
mod tests {
    use clap::ValueEnum;

    crate::choice! {
        /// A choice for the test.
        #[derive(Clone, Copy, Debug, PartialEq)]
        enum Weather {
            /// Documented.
            Fair => "fair",
            HeavyRain => "heavy rain",
        }
    }

    #[test]
    fn a_choice_is_written_once_and_read_back_by_its_name() {
        assert_eq!(Weather::ALL, [Weather::Fair, Weather::HeavyRain]);
        assert_eq!(Weather::HeavyRain.name(), "heavy rain");
        assert_eq!(Weather::HeavyRain.to_string(), "heavy rain");
        assert_eq!(
            Weather::from_str("Heavy Rain", true),
            Ok(Weather::HeavyRain)
        );
        let e = super::parse::<Weather>("snow", "the weather").unwrap_err();
        assert_eq!(e, "'snow' is not the weather (fair, heavy rain)");
    }

    /// Choices that parse themselves (a derived `ValueEnum`, or the first word of a name) still
    /// read back every name they print.
    #[test]
    fn choices_with_their_own_values_parse_what_they_print() {
        use crate::scene::camera_path::PathKind;
        use crate::scene::foliage::FoliagePolicy;
        use crate::scene::kind::SceneKind;
        fn round_trip<T: ValueEnum + PartialEq + std::fmt::Debug + Copy>(
            all: &[T],
            name: fn(T) -> &'static str,
        ) {
            for &v in all {
                let first = name(v).split(' ').next().unwrap();
                assert_eq!(super::parse::<T>(first, "a choice"), Ok(v), "{}", name(v));
            }
        }
        round_trip(&SceneKind::ALL, SceneKind::name);
        round_trip(&PathKind::ALL, PathKind::name);
        round_trip(&FoliagePolicy::ALL, FoliagePolicy::name);
        assert_eq!(SceneKind::ALL.len(), SceneKind::value_variants().len());
    }
}
