//! The JSON of a spec's `mesh`: one key naming the kind (`{"model": NAME}`,
//! `{"corner": {"n": 33}}`, ...), as serde's externally tagged enums read it, or a user's file
//! with an optional pin, two keys in either order (`{"file": "PATH", "sha256": "…"}`).
//!
//! [`MeshSource`] derives its one-key form with `#[serde(remote = "Self")]`; the impls here read
//! the first key and either parse the file form or hand the key and its value to the derived
//! code through `Keyed`, so that a parse error inside a procedural mesh keeps its path
//! (`scenes[0].instances[1].mesh.corner.n`).

use super::MeshSource;
use serde::de::{self, DeserializeSeed, IntoDeserializer, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// A user's mesh file as a spec names it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MeshFile {
    /// The path as written in the spec: relative to the spec file's folder, or absolute.
    pub file: String,
    /// The sha256 the file's bytes must have (lowercase hex), if pinned.
    pub sha256: Option<String>,
}

impl MeshFile {
    /// The label in tables, the plan and messages: the file's name without its folders.
    pub fn label(&self) -> String {
        std::path::Path::new(&self.file)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.file.clone())
    }
}

/// Every key a mesh may start with, for the error on an unknown one.
const KEYS: &[&str] = &[
    "model",
    "file",
    "corner",
    "cube_with_hole",
    "supershape",
    "sphere",
    "plane",
    "ellipsoid",
];

impl Serialize for MeshSource {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            MeshSource::File(f) => {
                let mut m = s.serialize_map(None)?;
                m.serialize_entry("file", &f.file)?;
                if let Some(h) = &f.sha256 {
                    m.serialize_entry("sha256", h)?;
                }
                m.end()
            }
            other => MeshSource::serialize(other, s),
        }
    }
}

impl<'de> Deserialize<'de> for MeshSource {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_map(MeshVisitor)
    }
}

struct MeshVisitor;

impl<'de> Visitor<'de> for MeshVisitor {
    type Value = MeshSource;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(
            f,
            "a mesh: one of {{\"model\": NAME}}, {{\"file\": PATH, \"sha256\": HEX}} or a \
             procedural mesh ({})",
            KEYS[2..].join(", ")
        )
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<MeshSource, A::Error> {
        let Some(key) = map.next_key::<String>()? else {
            return Err(de::Error::invalid_length(0, &self));
        };
        if key == "file" || key == "sha256" {
            let mut file = None;
            let mut sha256 = None;
            let mut key = Some(key);
            while let Some(k) = key {
                match k.as_str() {
                    "file" if file.is_none() => file = Some(map.next_value::<String>()?),
                    "sha256" if sha256.is_none() => sha256 = Some(map.next_value::<String>()?),
                    "file" | "sha256" => return Err(de::Error::duplicate_field("file or sha256")),
                    other => return Err(de::Error::unknown_field(other, &["file", "sha256"])),
                }
                key = map.next_key::<String>()?;
            }
            let file = file.ok_or_else(|| de::Error::missing_field("file"))?;
            return Ok(MeshSource::File(MeshFile { file, sha256 }));
        }
        if !KEYS.contains(&key.as_str()) {
            return Err(de::Error::unknown_variant(&key, KEYS));
        }
        let mesh = map.next_value_seed(KeyedSeed(key))?;
        if let Some(extra) = map.next_key::<String>()? {
            return Err(de::Error::custom(format!(
                "a mesh has one key (its kind); `{extra}` is one too many"
            )));
        }
        Ok(mesh)
    }
}

/// Deserialises the value of a mesh's kind key with the derived one-key code.
struct KeyedSeed(String);

impl<'de> DeserializeSeed<'de> for KeyedSeed {
    type Value = MeshSource;

    fn deserialize<D: Deserializer<'de>>(self, value: D) -> Result<MeshSource, D::Error> {
        MeshSource::deserialize(Keyed { key: self.0, value })
    }
}

/// An externally tagged enum whose tag was already read: `key` names the variant, `value`
/// deserialises its content.
struct Keyed<D> {
    key: String,
    value: D,
}

impl<'de, D: Deserializer<'de>> Deserializer<'de> for Keyed<D> {
    type Error = D::Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, D::Error> {
        visitor.visit_enum(self)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map struct enum
        identifier ignored_any
    }
}

impl<'de, D: Deserializer<'de>> de::EnumAccess<'de> for Keyed<D> {
    type Error = D::Error;
    type Variant = Content<D>;

    fn variant_seed<V: DeserializeSeed<'de>>(
        self,
        seed: V,
    ) -> Result<(V::Value, Content<D>), D::Error> {
        let tag = seed.deserialize(self.key.into_deserializer())?;
        Ok((tag, Content(self.value)))
    }
}

/// The content of a variant, read from the value's own deserialiser.
struct Content<D>(D);

impl<'de, D: Deserializer<'de>> de::VariantAccess<'de> for Content<D> {
    type Error = D::Error;

    fn unit_variant(self) -> Result<(), D::Error> {
        <()>::deserialize(self.0)
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Result<T::Value, D::Error> {
        seed.deserialize(self.0)
    }

    fn tuple_variant<V: Visitor<'de>>(self, len: usize, v: V) -> Result<V::Value, D::Error> {
        self.0.deserialize_tuple(len, v)
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_struct("", fields, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(json: &str) -> Result<MeshSource, String> {
        let de = &mut serde_json::Deserializer::from_str(json);
        serde_path_to_error::deserialize(de).map_err(|e| format!("{}: {}", e.path(), e.inner()))
    }

    #[test]
    fn file_form_reads_both_keys_in_either_order_and_round_trips() {
        let pinned = MeshSource::File(MeshFile {
            file: "../meshes/a.obj".into(),
            sha256: Some("ab".into()),
        });
        assert_eq!(
            parse(r#"{"file": "../meshes/a.obj", "sha256": "ab"}"#).unwrap(),
            pinned
        );
        assert_eq!(
            parse(r#"{"sha256": "ab", "file": "../meshes/a.obj"}"#).unwrap(),
            pinned
        );
        let text = serde_json::to_string(&pinned).unwrap();
        assert_eq!(text, r#"{"file":"../meshes/a.obj","sha256":"ab"}"#);
        assert_eq!(parse(&text).unwrap(), pinned);
        let bare = parse(r#"{"file": "b.ply"}"#).unwrap();
        assert_eq!(
            bare,
            MeshSource::File(MeshFile {
                file: "b.ply".into(),
                sha256: None
            })
        );
        assert_eq!(bare.label(), "b.ply");
    }

    #[test]
    fn one_key_forms_round_trip_and_keep_their_error_paths() {
        for json in [
            r#"{"model":"bunny_npm"}"#,
            r#"{"corner":{"n":33}}"#,
            r#"{"sphere":{"radius":1.0,"stacks":4,"slices":8}}"#,
        ] {
            let m = parse(json).unwrap();
            assert_eq!(serde_json::to_string(&m).unwrap(), json);
        }
        let e = parse(r#"{"corner": {"n": "x"}}"#).unwrap_err();
        assert!(e.starts_with("corner.n:"), "{e}");
        let e = parse(r#"{"corner": {"n": 3, "m": 1}}"#).unwrap_err();
        assert!(e.contains("unknown field `m`"), "{e}");
    }

    #[test]
    fn malformed_meshes_are_refused_naming_the_key() {
        let e = parse(r#"{"cornr": {"n": 3}}"#).unwrap_err();
        assert!(
            e.contains("unknown variant `cornr`") && e.contains("`file`"),
            "{e}"
        );
        let e = parse(r#"{"file": "a.obj", "sha": "x"}"#).unwrap_err();
        assert!(e.contains("unknown field `sha`"), "{e}");
        let e = parse(r#"{"sha256": "ab"}"#).unwrap_err();
        assert!(e.contains("missing field `file`"), "{e}");
        let e = parse(r#"{"file": "a.obj", "file": "b.obj"}"#).unwrap_err();
        assert!(e.contains("duplicate field"), "{e}");
        let e = parse(r#"{"model": "a", "corner": {"n": 3}}"#).unwrap_err();
        assert!(e.contains("one too many"), "{e}");
        let e = parse(r#"{}"#).unwrap_err();
        assert!(e.contains("a mesh"), "{e}");
        let e = parse(r#"{"file": 3}"#).unwrap_err();
        assert!(e.starts_with("file:"), "{e}");
    }
}
