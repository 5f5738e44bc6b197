//! The well-formedness of a URDF's XML, checked before it is read, so that a file cut short or
//! with elements out of order is refused with its line.

/// What makes `text` not well-formed XML, with its line (an element left open at the end,
/// as in a file cut short, names the element and the line it opened on); `None` if it is.
pub fn xml_problem(text: &str) -> Option<String> {
    use quick_xml::events::Event;
    let line = |at: u64| {
        let at = usize::try_from(at).unwrap_or(usize::MAX).min(text.len());
        1 + text.as_bytes()[..at]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    };
    let mut reader = quick_xml::Reader::from_str(text);
    let mut open: Vec<(String, usize)> = Vec::new();
    let mut elements = 0;
    loop {
        let at = reader.buffer_position();
        match reader.read_event() {
            Err(e) => return Some(format!("line {}: {e}", line(reader.error_position()))),
            Ok(Event::Start(e)) => {
                elements += 1;
                open.push((
                    String::from_utf8_lossy(e.name().as_ref()).into_owned(),
                    line(at),
                ));
            }
            Ok(Event::Empty(_)) => elements += 1,
            Ok(Event::End(_)) => {
                open.pop();
            }
            Ok(Event::Eof) if elements == 0 => {
                return Some(format!(
                    "no XML element in its {} lines (an empty file?)",
                    line(text.len() as u64)
                ));
            }
            Ok(Event::Eof) => {
                return open.last().map(|(name, from)| {
                    format!(
                        "the file ends at line {} inside <{name}> (opened on line {from}): is it \
                         cut short?",
                        line(text.trim_end().len() as u64)
                    )
                });
            }
            Ok(_) => {}
        }
    }
}
