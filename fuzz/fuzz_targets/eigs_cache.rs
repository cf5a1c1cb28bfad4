#![no_main]
// The eigenpair cache parser (symcorr::cache::decode) on arbitrary bytes: it must
// return Ok or a typed error — never panic, hang or allocate beyond the input's size — and
// whatever it accepts must encode back to exactly the same bytes (so nothing is read but what
// is there). Three views of each input: the raw bytes; the bytes behind a valid magic and
// version with a recomputed checksum; and a file of the right length for a small n and k
// (taken from the input) whose header and data are the input, resealed — the checksum and
// length checks would otherwise stop nearly every input before the content checks.

use libfuzzer_sys::fuzz_target;
use sha2::{Digest, Sha256};
use symcorr::cache::{decode, encode, FORMAT_VERSION, MAGIC};

const HEADER: usize = 112;
const SUM: usize = 32;

fn reseal(b: &mut [u8]) {
    let body = b.len() - SUM;
    let s: [u8; 32] = Sha256::digest(&b[..body]).into();
    b[body..].copy_from_slice(&s);
}

fn check(b: &[u8]) {
    if let Ok(f) = decode(b) {
        let again = encode(&f.key, &f.eigenpairs, &f.mass).expect("a decoded file encodes");
        assert_eq!(again, b, "decode → encode is not the identity");
    }
}

fuzz_target!(|data: &[u8]| {
    check(data);

    let mut framed = MAGIC.to_vec();
    framed.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    framed.extend_from_slice(data);
    if framed.len() >= HEADER + SUM {
        reseal(&mut framed);
        check(&framed);
    }

    if data.len() < 2 {
        return;
    }
    let n = 1 + (data[0] % 8) as usize;
    let k = 1 + (data[1] as usize) % n;
    let len = HEADER + 8 * (k + n * k + n) + SUM;
    let rest = &data[2..];
    let mut b: Vec<u8> = if rest.is_empty() {
        vec![0; len]
    } else {
        rest.iter().copied().cycle().take(len).collect()
    };
    b[..8].copy_from_slice(&MAGIC);
    b[8..12].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
    // Reserved 0 and the true n, k unless the first byte's high bit asks to keep its own bytes.
    if data[0] & 0x80 == 0 {
        b[12..16].fill(0);
        b[48..56].copy_from_slice(&(n as u64).to_le_bytes());
        b[56..64].copy_from_slice(&(k as u64).to_le_bytes());
    }
    reseal(&mut b);
    check(&b);
});
