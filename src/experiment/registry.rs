//! A registry of plug-ins (render kinds, methods): the entries built into this build, then
//! those added at run time, looked up by name. `experiment::kinds` and `experiment::methods` each keep
//! one.

use std::sync::RwLock;

/// What a registry holds: a copyable entry with a name.
pub trait Entry: Copy + 'static {
    fn name(&self) -> &'static str;
}

/// The built-in entries and those [`Registry::register`] added.
pub struct Registry<E: Entry> {
    built_in: &'static [E],
    extra: RwLock<Vec<E>>,
    /// What an entry is, for errors ("render kind", "method").
    what: &'static str,
}

impl<E: Entry> Registry<E> {
    pub const fn new(built_in: &'static [E], what: &'static str) -> Registry<E> {
        Registry {
            built_in,
            extra: RwLock::new(Vec::new()),
            what,
        }
    }

    /// Adds an entry; refused when its name is taken.
    pub fn register(&self, entry: E) -> Result<(), String> {
        let mut extra = self.extra.write().unwrap_or_else(|e| e.into_inner());
        if self.find(&extra, entry.name()).is_some() {
            return Err(format!(
                "a {} \"{}\" exists already",
                self.what,
                entry.name()
            ));
        }
        extra.push(entry);
        Ok(())
    }

    fn find(&self, extra: &[E], name: &str) -> Option<E> {
        self.built_in
            .iter()
            .chain(extra.iter())
            .find(|e| e.name() == name)
            .copied()
    }

    /// The entry named `name`.
    pub fn lookup(&self, name: &str) -> Option<E> {
        let extra = self.extra.read().unwrap_or_else(|e| e.into_inner());
        self.find(&extra, name)
    }

    /// The entry named `name`, or the error a spec's `key` gets: the unknown name and every
    /// name this build has.
    pub fn lookup_for(&self, key: &str, name: &str) -> Result<E, String> {
        self.lookup(name).ok_or_else(|| {
            let names: Vec<String> = self.names().iter().map(|n| format!("\"{n}\"")).collect();
            format!(
                "`{key}`: unknown {} \"{name}\"; this build has {}",
                self.what,
                names.join(", ")
            )
        })
    }

    /// Every entry's name, built-in ones first.
    pub fn names(&self) -> Vec<&'static str> {
        let extra = self.extra.read().unwrap_or_else(|e| e.into_inner());
        self.built_in
            .iter()
            .chain(extra.iter())
            .map(|e| e.name())
            .collect()
    }
}

/// JSON keys, as a spec and a plug-in's options write them.
pub type Keys = serde_json::Map<String, serde_json::Value>;

/// A plug-in's own keys read into its options by `read` and written back by `to_json`, as the
/// spec keeps them; the written-back keys must read again (where a number its type cannot hold,
/// 1e39 as an f32, was written back as null, they do not). The error names the entry: `what`
/// ("render", "method") and its `name`.
pub fn read_and_write_back<O: ?Sized>(
    what: &str,
    name: &str,
    read: fn(serde_json::Value) -> Result<Box<O>, serde_json::Error>,
    to_json: impl Fn(&O) -> Keys,
    own: Keys,
) -> Result<Keys, String> {
    let options = read(serde_json::Value::Object(own)).map_err(|e| format!("\"{name}\": {e}"))?;
    let keys = to_json(&options);
    read(serde_json::Value::Object(keys.clone())).map_err(|e| {
        format!("{what} \"{name}\": a number out of its type's range ({e} once read)")
    })?;
    Ok(keys)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy)]
    struct Named(&'static str);

    impl Entry for Named {
        fn name(&self) -> &'static str {
            self.0
        }
    }

    #[test]
    fn an_unknown_name_is_refused_naming_the_key_and_every_entry() {
        static R: Registry<Named> = Registry::new(&[Named("a"), Named("b")], "toy");
        assert_eq!(
            R.register(Named("a")).unwrap_err(),
            "a toy \"a\" exists already"
        );
        R.register(Named("c")).unwrap();
        assert_eq!(R.lookup_for("what", "c").map(|e| e.0), Ok("c"));
        assert_eq!(
            R.lookup_for("what", "d").map(|e| e.0).unwrap_err(),
            "`what`: unknown toy \"d\"; this build has \"a\", \"b\", \"c\""
        );
    }
}
