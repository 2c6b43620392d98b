#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = cltrace_fuzz::texture(data);
});
