//! RON text as scene files write it: the `strata` CLI's parser options (newtype
//! variants unwrapped, so `Designed(guidance: Curvature())` reads as in a scene file).
//!
//! Input: text. Output: a deserialized value or the parser's message with its line
//! and column. Cost: linear in the text.

/// Parses `text` as RON with the scene files' extensions.
pub fn parse<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, String> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
        .from_str(text)
        .map_err(|e| e.to_string())
}
