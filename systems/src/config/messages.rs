//! Readable messages for RON syntax errors in scene files. ron reports the state of its
//! parser (`count: 2000.5` gives "Expected comma", `field: 3.0` suggests the raw
//! identifier `r#3.0`); where the mistake is recognisable, the message here says what
//! the option expects and what it found instead.

use ron::error::{Error, SpannedError};

/// The message for a parse `error` of scene `text`. `reparse` parses a text with the
/// same options, so that a value that is not a name can be replaced by a placeholder
/// name to learn which names are accepted where it stands.
pub(super) fn parse_message(
    text: &str,
    error: &SpannedError,
    reparse: impl Fn(&str) -> Option<SpannedError>,
) -> String {
    let fallback = error.code.to_string();
    let Some(at) = char_offset(text, error.span.start.line, error.span.start.col) else {
        return fallback;
    };
    let Some((start, end)) = token_around(text, at) else {
        return fallback;
    };
    let token = &text[start..end];
    let key = key_before(text, start).map_or(String::new(), |k| format!("`{k}`: "));
    match &error.code {
        // `2000.5` where an integer is expected: ron reads `2000` and stops at `.5`.
        Error::ExpectedComma | Error::ExpectedStructLikeEnd | Error::ExpectedArrayEnd
            if is_fraction_after_digits(text, at) =>
        {
            format!("{key}expected an integer, found `{token}`")
        }
        Error::ExpectedInteger | Error::InvalidIntegerDigit { .. } | Error::IntegerOutOfBounds => {
            integer_message(&key, token, &fallback)
        }
        Error::ExpectedFloat => format!("{key}expected a number, found `{token}`"),
        Error::ExpectedIdentifier
        | Error::InvalidIdentifier(_)
        | Error::SuggestRawIdentifier(_) => {
            name_message(text, start, end, &key, &reparse).unwrap_or(fallback)
        }
        _ => fallback,
    }
}

/// Where an integer was expected and `token` is not one.
fn integer_message(key: &str, token: &str, fallback: &str) -> String {
    let digits = token.trim_start_matches(['-', '+']);
    let integral = !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit() || b == b'_');
    if integral && token.starts_with('-') {
        format!("{key}expected a non-negative integer, found `{token}`")
    } else if integral {
        format!("{key}the integer `{token}` is out of range here ({fallback})")
    } else {
        format!("{key}expected an integer, found `{token}`")
    }
}

/// Where a name (an enum variant such as `Constant(...)`) was expected: the accepted
/// names, learnt by parsing the text again with a placeholder name in the token's place.
fn name_message(
    text: &str,
    start: usize,
    end: usize,
    key: &str,
    reparse: &impl Fn(&str) -> Option<SpannedError>,
) -> Option<String> {
    const PLACEHOLDER: &str = "NotAName";
    let token = &text[start..end];
    let replaced = format!("{}{PLACEHOLDER}{}", &text[..start], &text[end..]);
    match reparse(&replaced)?.code {
        Error::NoSuchEnumVariant {
            expected, outer, ..
        } => {
            let names = expected
                .iter()
                .map(|n| format!("`{n}`"))
                .collect::<Vec<_>>()
                .join(", ");
            let of = outer.map_or(String::new(), |o| format!(" (a `{o}`)"));
            Some(format!("{key}expected one of {names}{of}, found `{token}`"))
        }
        _ => None,
    }
}

/// The byte offset of 1-based `line` and `column` (in characters) in `text`.
fn char_offset(text: &str, line: usize, column: usize) -> Option<usize> {
    let line_start = if line <= 1 {
        0
    } else {
        text.match_indices('\n').nth(line - 2)?.0 + 1
    };
    let rest = &text[line_start..];
    let within = rest
        .char_indices()
        .nth(column.checked_sub(1)?)
        .map_or(rest.len(), |(i, _)| i);
    Some(line_start + within)
}

/// Whether `c` belongs to a value token (a number, a name, a quoted word).
fn is_token_char(c: char) -> bool {
    !c.is_whitespace() && !matches!(c, ',' | '(' | ')' | '[' | ']' | '{' | '}' | ':')
}

/// The byte range of the token that contains byte `at` or ends just before it, or else
/// of the next token after white space (ron may point at the space before a value).
fn token_around(text: &str, mut at: usize) -> Option<(usize, usize)> {
    let inside = text[at..].chars().next().is_some_and(is_token_char);
    let before = text[..at].chars().next_back().is_some_and(is_token_char);
    if !inside && !before {
        let skipped = text[at..].len() - text[at..].trim_start().len();
        if skipped == 0
            || !text[at + skipped..]
                .chars()
                .next()
                .is_some_and(is_token_char)
        {
            return None;
        }
        at += skipped;
    }
    let start = text[..at]
        .char_indices()
        .rev()
        .take_while(|&(_, c)| is_token_char(c))
        .last()
        .map_or(at, |(i, _)| i);
    let end = text[at..]
        .char_indices()
        .find(|&(_, c)| !is_token_char(c))
        .map_or(text.len(), |(i, _)| at + i);
    Some((start, end))
}

/// The option name in `name: value` when a value starts at byte `start`.
fn key_before(text: &str, start: usize) -> Option<&str> {
    let before = text[..start].trim_end().strip_suffix(':')?.trim_end();
    let key_start = before
        .char_indices()
        .rev()
        .take_while(|&(_, c)| c.is_ascii_alphanumeric() || c == '_')
        .last()?
        .0;
    Some(&before[key_start..])
}

/// Whether byte `at` starts a fraction or an exponent right after a digit (`2000|.5`).
fn is_fraction_after_digits(text: &str, at: usize) -> bool {
    text[at..].starts_with(['.', 'e', 'E'])
        && text[..at]
            .chars()
            .next_back()
            .is_some_and(|c| c.is_ascii_digit())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_count_characters() {
        let text = "ab\né: x";
        assert_eq!(char_offset(text, 1, 1), Some(0));
        assert_eq!(char_offset(text, 2, 1), Some(3));
        assert_eq!(char_offset(text, 2, 2), Some(5)); // 'é' is two bytes
        assert_eq!(char_offset(text, 2, 4), Some(7));
        assert_eq!(char_offset(text, 3, 1), None);
    }

    #[test]
    fn tokens_and_keys() {
        let text = "(count: 2000.5, seed: 1)";
        let dot = text.find('.').expect("dot");
        let (s, e) = token_around(text, dot).expect("token");
        assert_eq!(&text[s..e], "2000.5");
        assert_eq!(key_before(text, s), Some("count"));
        let comma = text.find(',').expect("comma");
        assert_eq!(
            token_around(text, comma).map(|(s, e)| &text[s..e]),
            Some("2000.5")
        );
        assert_eq!(token_around(text, 0), None);
        let spaced = "(seed:  true)";
        let space = spaced.find(' ').expect("space");
        assert_eq!(
            token_around(spaced, space).map(|(s, e)| &spaced[s..e]),
            Some("true")
        );
        assert!(is_fraction_after_digits(text, dot));
        assert!(!is_fraction_after_digits(text, s));
    }

    #[test]
    fn integers_that_are_not() {
        assert!(integer_message("", "-5", "x").contains("non-negative"));
        assert!(integer_message("", "1e3", "x").contains("expected an integer"));
        assert!(integer_message("", "99999999999999999999999", "x").contains("out of range"));
    }
}
