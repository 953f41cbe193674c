//! JSON as the commands print and write it: every measured fraction rounded to six
//! significant digits, so that a frame time reads `401.521`, not `401.52149399999996` (the
//! float the sum of a few timestamps happens to land on). Whole numbers stay exact.

use serde::Serialize;

/// Significant digits a fraction keeps.
const DIGITS: i32 = 6;

/// `x` to [`DIGITS`] significant digits.
fn round(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() || x.fract() == 0.0 {
        return x;
    }
    let scale = 10f64.powi(DIGITS - 1 - x.abs().log10().floor() as i32);
    let rounded = (x * scale).round() / scale;
    if rounded.is_finite() { rounded } else { x }
}

/// JSON text `text` with every fractional number rounded, in place: keys keep the order
/// the structs give them (a `serde_json::Value` would sort them).
fn tidy(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.char_indices().peekable();
    let mut in_string = false;
    while let Some((i, c)) = chars.next() {
        if in_string {
            out.push(c);
            if c == '\\' {
                if let Some((_, escaped)) = chars.next() {
                    out.push(escaped);
                }
            } else if c == '"' {
                in_string = false;
            }
            continue;
        }
        if c == '"' {
            in_string = true;
            out.push(c);
        } else if c == '-' || c.is_ascii_digit() {
            let mut end = i + c.len_utf8();
            while let Some(&(j, d)) = chars.peek() {
                if d.is_ascii_digit() || matches!(d, '.' | 'e' | 'E' | '+' | '-') {
                    end = j + d.len_utf8();
                    chars.next();
                } else {
                    break;
                }
            }
            let token = &text[i..end];
            let fractional = token.contains(['.', 'e', 'E']);
            match token.parse::<f64>() {
                Ok(x) if fractional && x.is_finite() => {
                    let r = round(x);
                    // Shortest text that reads back as `r`; a whole number keeps its ".0".
                    let shown = format!("{r:?}");
                    out.push_str(&shown);
                }
                _ => out.push_str(token),
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// One line of JSON, rounded.
pub fn line<T: Serialize>(value: &T) -> serde_json::Result<String> {
    Ok(tidy(&serde_json::to_string(value)?))
}

/// Indented JSON, rounded.
pub fn pretty<T: Serialize>(value: &T) -> serde_json::Result<String> {
    Ok(tidy(&serde_json::to_string_pretty(value)?))
}

/// `--json[=FILE]` as every command that has it reads it: absent, the command prints its
/// table; bare, it prints the JSON instead; with a file, it prints the table and writes the
/// JSON there too. `FILE` is checked before the work starts ([`json_file`]).
pub type JsonOut = Option<Option<std::path::PathBuf>>;

/// Prints `table` or `value` as `json` says, and writes the file it names.
pub fn emit(json: &JsonOut, value: &impl Serialize, table: &str) -> anyhow::Result<()> {
    match json {
        Some(None) => println!("{}", pretty(value)?),
        Some(Some(file)) => {
            print!("{table}");
            crate::atomic::write(file, pretty(value)?.as_bytes())?;
        }
        None => print!("{table}"),
    }
    Ok(())
}

/// The file `--json=FILE` names, if any: checked before a long run, so that a run is not lost
/// to a path that cannot be written.
pub fn json_file(json: &JsonOut) -> Option<&std::path::PathBuf> {
    json.as_ref().and_then(|f| f.as_ref())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fractions_keep_six_digits_and_whole_numbers_stay() {
        let v = serde_json::json!({
            "ms": 401.52149399999996,
            "small": 0.000412345678,
            "count": 12345678901u64,
            "whole": 3.0,
            "list": [1.23456789, -98765.4321],
            "text": "a \"quoted\" 3.14159265 stays",
        });
        assert_eq!(
            line(&v).unwrap(),
            r#"{"count":12345678901,"list":[1.23457,-98765.4],"ms":401.521,"small":0.000412346,"text":"a \"quoted\" 3.14159265 stays","whole":3.0}"#
        );
    }
}
