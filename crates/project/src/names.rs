//! Enums read from the file by name, with the names listed in the error.

/// Reads a unit enum from its name in a rig file; any other value is answered with
/// the names that would do (`expected a method: "c2", "arap" or "lbc"`).
macro_rules! deserialize_by_name {
    ($ty:ident, $what:literal, [$($name:literal => $value:expr),+ $(,)?]) => {
        impl<'de> Deserialize<'de> for $ty {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct Names;
                impl serde::de::Visitor<'_> for Names {
                    type Value = $ty;
                    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                        let names = [$(concat!("\"", $name, "\"")),+];
                        let (last, rest) = names.split_last().unwrap_or((&"", &[]));
                        if rest.is_empty() {
                            write!(f, "{} {last}", $what)
                        } else {
                            write!(f, "{}: {} or {last}", $what, rest.join(", "))
                        }
                    }
                    fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<$ty, E> {
                        match s {
                            $($name => Ok($value),)+
                            _ => Err(E::invalid_value(serde::de::Unexpected::Str(s), &self)),
                        }
                    }
                }
                d.deserialize_str(Names)
            }
        }
    };
}
