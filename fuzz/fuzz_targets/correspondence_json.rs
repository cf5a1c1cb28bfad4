#![no_main]
// The symcorr.correspondence/1 reader (symcorr::formats::CorrespondenceFile::from_json_str) on
// arbitrary bytes decoded as lossy UTF-8: it must return Ok or a typed error naming the file,
// never panic; and whatever it accepts must write (to_json) and read back to the same value.

use libfuzzer_sys::fuzz_target;
use symcorr::formats::CorrespondenceFile;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    match CorrespondenceFile::from_json_str(&text, "fuzz.json") {
        Ok(doc) => {
            let back = CorrespondenceFile::from_json_str(&doc.to_json(), "fuzz.json")
                .expect("the writer's output reads back");
            assert_eq!(back, doc, "correspondence round trip changed the value");
        }
        Err(e) => assert!(e.to_string().starts_with("fuzz.json: "), "{e}"),
    }
});
