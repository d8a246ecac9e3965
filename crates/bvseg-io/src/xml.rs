//! What the XML writers (MuJoCo MJCF, URDF) share.

/// Text for an XML attribute value, quoted with either quote; control characters, which XML
/// 1.0 does not allow, become `_`.
pub(crate) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if c.is_control() => out.push('_'),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::escape;

    #[test]
    fn markup_and_control_characters_are_replaced() {
        assert_eq!(escape("a<b>&\"c'd\te"), "a&lt;b&gt;&amp;&quot;c&apos;d_e");
        assert_eq!(escape("left_hip"), "left_hip");
    }
}
