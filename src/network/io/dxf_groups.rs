//! The group codes of an ASCII DXF read straight from its text, for what the `dxf` crate
//! drops: each group with the section (or block definition) it belongs to and its line.

/// One group: its code, its value (surrounding whitespace and `\r` trimmed) and the line its
/// code is on, counted from 1.
#[derive(Clone, Copy, Debug)]
pub(super) struct Group<'a> {
    pub code: i32,
    pub value: &'a [u8],
    pub line: usize,
}

/// Where a group is: among the model's entities, inside a block definition (its upper-case
/// name), or elsewhere (headers, tables, the records that open and close sections and blocks).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Place<'a> {
    Entities,
    Block(&'a str),
    Other,
}

/// Calls `f` on every group of the file in order, with its place. Stops at a code line that is
/// not an integer (the parser reports such a file).
pub(super) fn walk_groups<'a>(bytes: &'a [u8], mut f: impl FnMut(Place, Group<'a>)) {
    #[derive(PartialEq)]
    enum Section {
        Entities,
        Blocks,
        Other,
    }
    let mut lines = bytes
        .split(|&b| b == b'\n')
        .map(|l| l.trim_ascii())
        .enumerate();
    let mut section = Section::Other;
    let mut after_section = false;
    // Inside BLOCKS: the block being defined, and whether its name (code 2) is still to come.
    let mut block: Option<String> = None;
    let mut naming = false;
    while let (Some((n, code)), Some((_, value))) = (lines.next(), lines.next()) {
        let Some(code) = std::str::from_utf8(code)
            .ok()
            .and_then(|c| c.parse::<i32>().ok())
        else {
            break;
        };
        let group = Group {
            code,
            value,
            line: n + 1,
        };
        if code == 0 {
            after_section = value == b"SECTION";
            match value {
                b"ENDSEC" => section = Section::Other,
                b"BLOCK" if section == Section::Blocks => {
                    naming = true;
                    block = None;
                }
                b"ENDBLK" if section == Section::Blocks => block = None,
                _ => {}
            }
        } else if code == 2 && after_section {
            section = match value {
                b"ENTITIES" => Section::Entities,
                b"BLOCKS" => Section::Blocks,
                _ => Section::Other,
            };
            after_section = false;
            f(Place::Other, group);
            continue;
        } else if code == 2 && naming {
            block = Some(String::from_utf8_lossy(value).to_ascii_uppercase());
            naming = false;
            f(Place::Other, group);
            continue;
        }
        let place = match (&section, &block) {
            (Section::Entities, _) => Place::Entities,
            (Section::Blocks, Some(b)) => Place::Block(b),
            _ => Place::Other,
        };
        f(place, group);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_are_placed_in_their_section_and_block() {
        let d =
            "0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n8\n0\n2\nb1\n0\nLINE\n8\n0\n0\nENDBLK\n0\nENDSEC\n\
                 0\nSECTION\n2\nENTITIES\n0\nHATCH\n91\n1\n0\nENDSEC\n0\nEOF\n";
        let mut seen = Vec::new();
        walk_groups(d.as_bytes(), |place, g| {
            if g.code == 0 {
                let name = String::from_utf8_lossy(g.value).into_owned();
                seen.push((format!("{place:?}"), name, g.line));
            }
        });
        let names: Vec<(&str, &str, usize)> = seen
            .iter()
            .map(|(p, n, l)| (p.as_str(), n.as_str(), *l))
            .collect();
        assert_eq!(
            names,
            [
                ("Other", "SECTION", 1),
                ("Other", "BLOCK", 5),
                ("Block(\"B1\")", "LINE", 11),
                ("Other", "ENDBLK", 15),
                ("Other", "ENDSEC", 17),
                ("Other", "SECTION", 19),
                ("Entities", "HATCH", 23),
                ("Other", "ENDSEC", 27),
                ("Other", "EOF", 29),
            ]
        );
    }
}
