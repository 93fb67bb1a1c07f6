//! A framing pass over an ArduPilot DataFlash `.bin` before it is parsed:
//! where each message starts (`0xA3 0x95 type`, lengths from the FMT
//! messages), how many bytes between them are garbage, and whether the file
//! ends partway through a message. The `ardupilot-binlog` parser skips both
//! silently; this pass is what lets the CLI say how far a log was read.

/// Message type of FMT, and its fixed length.
const FMT_TYPE: u8 = 128;
const FMT_LEN: usize = 89;
const MAGIC: [u8; 2] = [0xA3, 0x95];

/// What [`scan`] found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct BinScan {
    /// File length, bytes.
    pub len: usize,
    /// Complete messages of a known type.
    pub messages: usize,
    /// Bytes skipped between messages (not a header, or a type no FMT
    /// defined).
    pub garbage_bytes: usize,
    /// Separate runs of such bytes.
    pub garbage_runs: usize,
    /// Offset of the first garbage byte.
    pub first_garbage_at: Option<usize>,
    /// Offset of a last message the file cuts short.
    pub truncated_at: Option<usize>,
}

impl BinScan {
    /// One clause per problem (`stopped at byte N: truncated message`,
    /// `skipped K bytes of garbage …`), or `None` for a clean file.
    pub fn describe_problems(&self) -> Option<String> {
        let mut p = Vec::new();
        if self.garbage_bytes > 0 {
            p.push(format!(
                "skipped {} bytes that are not valid messages in {} place(s), the first at byte {}",
                self.garbage_bytes,
                self.garbage_runs,
                self.first_garbage_at.unwrap_or(0)
            ));
        }
        if let Some(at) = self.truncated_at {
            p.push(format!(
                "stopped at byte {at} of {}: truncated message",
                self.len
            ));
        }
        (!p.is_empty()).then(|| p.join("; "))
    }
}

/// Frames `bytes` as DataFlash messages (never panics, any input).
pub fn scan(bytes: &[u8]) -> BinScan {
    let mut lens: [Option<usize>; 256] = [None; 256];
    lens[usize::from(FMT_TYPE)] = Some(FMT_LEN);
    let mut s = BinScan {
        len: bytes.len(),
        ..BinScan::default()
    };
    let mut pos = 0usize;
    let mut in_garbage = false;
    while pos < bytes.len() {
        let header = bytes.get(pos..pos + 3);
        let msg_len = match header {
            Some([a, b, t]) if [*a, *b] == MAGIC => lens[usize::from(*t)],
            _ => None,
        };
        let Some(msg_len) = msg_len else {
            if header.is_none() && !in_garbage && s.messages > 0 && bytes[pos] == MAGIC[0] {
                // A header cut short at the very end.
                s.truncated_at = Some(pos);
                break;
            }
            if !in_garbage {
                s.garbage_runs += 1;
                s.first_garbage_at.get_or_insert(pos);
                in_garbage = true;
            }
            s.garbage_bytes += 1;
            pos += 1;
            continue;
        };
        let Some(msg) = bytes.get(pos..pos + msg_len) else {
            s.truncated_at = Some(pos);
            break;
        };
        in_garbage = false;
        // A FMT message defines another type's length. The FMT type's own
        // length is fixed: a FMT redefining itself (as a mutated file can)
        // would make later FMT messages shorter than their fields.
        if let Some(&[_, _, FMT_TYPE, typ, len, ..]) = msg.get(..5) {
            let len = usize::from(len);
            if len >= 3 && typ != FMT_TYPE {
                lens[usize::from(typ)] = Some(len);
            }
        }
        s.messages += 1;
        pos += msg_len;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fmt(typ: u8, len: u8) -> Vec<u8> {
        let mut m = vec![0xA3, 0x95, FMT_TYPE, typ, len];
        m.resize(FMT_LEN, 0);
        m
    }

    #[test]
    fn garbage_and_truncation_are_located() {
        let mut b = fmt(5, 6);
        b.extend([0xA3, 0x95, 5, 1, 2, 3]);
        b.extend([9, 9, 9]);
        b.extend([0xA3, 0x95, 5, 1, 2, 3]);
        b.extend([0xA3, 0x95, 5, 1]);
        let s = scan(&b);
        assert_eq!(s.messages, 3);
        assert_eq!((s.garbage_bytes, s.garbage_runs), (3, 1));
        assert_eq!(s.first_garbage_at, Some(FMT_LEN + 6));
        assert_eq!(s.truncated_at, Some(FMT_LEN + 15));
        let d = s.describe_problems().expect("problems");
        assert!(d.contains("truncated message"), "{d}");
        assert_eq!(scan(&fmt(5, 6)).describe_problems(), None);
        assert_eq!(scan(&[]).messages, 0);
    }

    #[test]
    fn a_fmt_redefining_fmt_is_ignored() {
        // Found by the dataflash_file fuzz target: FMT redefined FMT's own
        // length to 3, and the next FMT's fields were read out of bounds.
        let mut b = fmt(FMT_TYPE, 3);
        b.extend([0xA3, 0x95, FMT_TYPE]);
        b.extend(fmt(5, 6));
        let s = scan(&b);
        assert_eq!(s.messages, 2);
        assert_eq!(s.garbage_bytes, 3);
    }
}
