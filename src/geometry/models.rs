//! Real meshes by name, found through `$VISFIELD_MODELS`, then `data/models/`, then
//! `../shared/models/`, each checked against the sha256 in `data/models.json`.
