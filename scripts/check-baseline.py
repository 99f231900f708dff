#!/usr/bin/env python3
"""Checks that a shipped x86-64 binary (the rvtol executable, or the extension module inside
the Python wheel) runs on any x86-64 CPU: no instruction beyond the x86-64 baseline (SSE2)
outside functions that a dependency dispatches to at run time after checking the CPU.

Such functions carry their target feature in their name by the crates' convention
(matrixmultiply's `kernel_target_avx2`, memchr's `find_avx2`, rand_chacha's `impl_avx2`,
crc32fast's `calculate_avx512`, sha2's `*_shani`/`*_avx2`, pulp's `V3`/`V4::vectorize`,
...); every other function must be baseline. Instructions are classified by mnemonic and register (objdump -d):
a ymm/zmm/k register or a VEX/EVEX mnemonic (v...) is AVX or AVX-512; the SSE3, SSSE3,
SSE4.1/4.2, POPCNT, LZCNT, BMI1/2, FMA, AES, PCLMUL and SHA mnemonics are listed below.

Usage: scripts/check-baseline.py FILE [FILE.whl ...]   (a .whl is searched for its .so)
Exit 0 when every file is baseline, 1 with the offending functions listed.
"""
import re
import subprocess
import sys
import tempfile
import zipfile

EXTENSIONS = {
    "sse3": "addsubpd addsubps haddpd haddps hsubpd hsubps lddqu movddup movshdup movsldup",
    "ssse3": "pabsb pabsd pabsw palignr phaddd phaddsw phaddw phsubd phsubsw phsubw pmaddubsw "
             "pmulhrsw pshufb psignb psignd psignw",
    "sse4.1": "blendpd blendps blendvpd blendvps dppd dpps extractps insertps movntdqa mpsadbw "
              "packusdw pblendvb pblendw pcmpeqq pextrb pextrd pextrq phminposuw pinsrb pinsrd "
              "pinsrq pmaxsb pmaxsd pmaxud pmaxuw pminsb pminsd pminud pminuw pmovsxbd pmovsxbq "
              "pmovsxbw pmovsxdq pmovsxwd pmovsxwq pmovzxbd pmovzxbq pmovzxbw pmovzxdq pmovzxwd "
              "pmovzxwq pmuldq pmulld ptest roundpd roundps roundsd roundss",
    "sse4.2": "crc32 crc32b crc32w crc32l crc32q pcmpestri pcmpestrm pcmpistri pcmpistrm pcmpgtq",
    "popcnt/lzcnt": "popcnt lzcnt",
    # tzcnt is left out: it is encoded as rep bsf, which a CPU without BMI1 executes as
    # bsf, and LLVM emits it for the baseline only where the two agree (a nonzero input).
    "bmi": "andn bextr blsi blsmsk blsr bzhi mulx pdep pext rorx sarx shlx shrx",
    "aes/pclmul/sha": "aesdec aesdeclast aesenc aesenclast aesimc aeskeygenassist pclmulqdq "
                      "pclmullqlqdq pclmulhqlqdq pclmullqhqdq pclmulhqhqdq sha1msg1 sha1msg2 "
                      "sha1nexte sha1rnds4 sha256msg1 sha256msg2 sha256rnds2",
}
MNEMONIC = {m: ext for ext, names in EXTENSIONS.items() for m in names.split()}
# Legacy mnemonics that start with v but are baseline.
LEGACY_V = {"verr", "verw"}
DISPATCHED = re.compile(
    r"avx|sse3|ssse3|sse4|sse41|sse42|fma|bmi|popcnt|lzcnt|pclmul|shani|sha_ni|aesni"
    # sha2's SHA-NI block function, called after its cpufeatures check of sha, sse4.1, ssse3.
    r"|^sha2::sha256::x86::digest_blocks"
    # pulp's #[target_feature] wrappers of its x86-64-v3 (AVX2, FMA) and v4 (AVX-512)
    # levels: a V3/V4 value exists only once `try_new` has checked the CPU (Arch::new), and
    # rvtol's folds run inside them (crates/models/src/reducer/folds.rs).
    r"|^pulp::x86::v[34]::V[34]::vectorize::imp", re.I)


def extension_of(mnemonic, operands):
    if re.search(r"%[yz]mm|%k[0-7]", operands):
        return "avx512" if re.search(r"%zmm|%k[0-7]", operands) else "avx"
    if mnemonic.startswith("v") and mnemonic not in LEGACY_V:
        return "avx"
    if mnemonic.startswith("vfmadd") or mnemonic.startswith("vfnmadd"):
        return "fma"
    return MNEMONIC.get(mnemonic)


def scan(path):
    """{function: {extension: count}} of the non-baseline instructions of an ELF file."""
    dump = subprocess.run(["objdump", "-d", "--no-show-raw-insn", "-C", path],
                          capture_output=True, text=True, check=True).stdout
    found, function = {}, "?"
    header = re.compile(r"^[0-9a-f]+ <(.*)>:$")
    for line in dump.splitlines():
        match = header.match(line)
        if match:
            function = match.group(1)
            continue
        parts = line.split("\t")
        if len(parts) < 2 or not parts[-1].strip():
            continue
        fields = parts[-1].split(None, 1)
        mnemonic = fields[0]
        if mnemonic in ("rep", "repz", "repnz", "lock", "notrack", "bnd", "data16") and len(fields) > 1:
            fields = fields[1].split(None, 1)
            mnemonic = fields[0]
        operands = fields[1] if len(fields) > 1 else ""
        extension = extension_of(mnemonic, operands)
        if extension:
            counts = found.setdefault(function, {})
            counts[extension] = counts.get(extension, 0) + 1
    return found


def check(path, label):
    found = scan(path)
    offending = {f: c for f, c in found.items() if not DISPATCHED.search(f)}
    dispatched = sum(sum(c.values()) for f, c in found.items() if DISPATCHED.search(f))
    total = sum(sum(c.values()) for c in offending.values())
    print(f"{label}: {dispatched} non-baseline instructions in {len(found) - len(offending)} "
          f"run-time dispatched functions; {total} elsewhere")
    for function, counts in sorted(offending.items(), key=lambda item: -sum(item[1].values()))[:20]:
        print(f"  {sum(counts.values()):6}  {dict(sorted(counts.items()))}  {function[:150]}")
    return not offending


def main():
    ok = True
    for path in sys.argv[1:]:
        if path.endswith(".whl"):
            with zipfile.ZipFile(path) as wheel, tempfile.TemporaryDirectory() as folder:
                for name in wheel.namelist():
                    if name.endswith(".so"):
                        ok &= check(wheel.extract(name, folder), f"{path}:{name}")
        else:
            ok &= check(path, path)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    try:
        main()
    except BrokenPipeError:  # output piped to a reader that stopped early
        sys.exit(1)
