//! XML text helpers shared by the writers of XML formats (OpenDRIVE towns, PIE/JAAD annotations, OpenSCENARIO
//! clips): escaping of attribute values and text.

/// `s` with the five characters XML reserves escaped, for attribute values (double-quoted) and text.
pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}
