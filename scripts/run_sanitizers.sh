#!/usr/bin/env bash
# The sanitizer and fuzzing part of the test command (scripts/run_tests.sh runs it after the
# Release suite; docs/testing.md says what each step checks and what it costs):
#   1. the native GoogleTest suite built with AddressSanitizer + UndefinedBehaviorSanitizer;
#   2. tsan_render (tests/sanitizers) built with ThreadSanitizer: renders on four TBB threads;
#   3. each fuzz target (tests/fuzz) for LANTERN_FUZZ_SECONDS (default 30) from its seed corpus.
# Builds in build-asan/ and build-tsan/ (clang; only the library objects and what each step
# runs). Exits non-zero on the first failure. Arguments: the steps to run (asan tsan fuzz; all
# by default).
set -euo pipefail
cd "$(dirname "$0")/.."
STEPS=${*:-asan tsan fuzz}
FUZZ_SECONDS=${LANTERN_FUZZ_SECONDS:-30}
ASAN_DIR=${LANTERN_ASAN_BUILD_DIR:-build-asan}
TSAN_DIR=${LANTERN_TSAN_BUILD_DIR:-build-tsan}
# clang and its sanitizer/libFuzzer runtimes; llvm-14 for llvm-symbolizer (stack traces).
bash scripts/install_packages.sh clang libclang-rt-14-dev llvm-14
SYMBOLIZER=/usr/lib/llvm-14/bin/llvm-symbolizer
JOBS=$(nproc)
ROOT=$PWD
step() { echo "== $1 =="; START=$SECONDS; }
took() { echo "   ($((SECONDS - START)) s)"; }

common=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo
        "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g"
        -DLANTERN_BUILD_BENCH=OFF)

if [[ " $STEPS " == *" asan "* || " $STEPS " == *" fuzz "* ]]; then
  step "ASan + UBSan build ($ASAN_DIR)"
  # fuzzer-no-link: the same objects serve the tests and the fuzz targets (coverage hooks only).
  SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fsanitize=fuzzer-no-link"
  SAN+=" -fsanitize-ignorelist=$ROOT/tests/sanitizers/ubsan_ignore.txt -fno-omit-frame-pointer"
  cmake -S . -B "$ASAN_DIR" "${common[@]}" "-DCMAKE_CXX_FLAGS=$SAN" "-DCMAKE_C_FLAGS=$SAN" \
    "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined" -DLANTERN_BUILD_FUZZ=ON >/dev/null
  cmake --build "$ASAN_DIR" -j"$JOBS" --target lantern_tests fuzz_abi fuzz_vdb fuzz_exr_merge fuzz_image_file make_fuzz_seeds
  took
fi
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:external_symbolizer_path=$SYMBOLIZER"
export UBSAN_OPTIONS="print_stacktrace=1:external_symbolizer_path=$SYMBOLIZER"
export LSAN_OPTIONS="suppressions=$ROOT/tests/sanitizers/lsan.supp:print_suppressions=0"

if [[ " $STEPS " == *" asan "* ]]; then
  step "native tests under ASan + UBSan"
  # Two shards in parallel (one per core). Left out: the long statistical tests (15-70 s each in
  # Release, several times that under ASan), whose code shorter tests run: BDPT's agreement tests
  # (panoramas', lenses' and orthographic cameras' light tracing in the MIS-sum and camera tests;
  # the BDPT catcher in ShadowCatcher's matte test; scale, near clip and frosted globes in the
  # other BDPT tests), the lobes' furnace and chi-square loops (BsdfSanity, HairLobes.WhiteFurnace,
  # PhaseHG at g = -0.5 ... 0.5), the rough-metal furnace render (ApiFurnace's other renders), the
  # denoiser's statistics (Denoise.HalfVariancesAreUnbiased and KeepsTheMeanWithinTheNoise run its
  # code), the fog carried by a wall material (VolPath's other tests run that code). Measured under
  # ASan on the 2-core machine, the BDPT ones left out here took 27-82 s each, the fog 50 s.
  SLOW="Bdpt.AgreesWithVolumetricPathTracingInMedia:Bdpt.FullBdptAgreesWithPathTracing"
  SLOW+=":Bdpt.DoorSlabsBounceKindsAgreeWithPathTracing:Bdpt.LightLengthOneEqualsPathTracing"
  SLOW+=":BsdfFurnace.NewLobesConserveEnergy:HairLobes.SamplesFollowPdf"
  SLOW+=":ApiFurnace.RoughMetalSphereReflectsAsCyclesPerBounce:PhaseHG/PhaseChi2.SamplingFollowsPdf/0"
  SLOW+=":PhaseHG/PhaseChi2.SamplingFollowsPdf/4"
  SLOW+=":Bdpt.OrthographicAgreesWithPathTracing:Bdpt.DepthOfFieldAndPanoramasAgreeWithPathTracing"
  SLOW+=":Bdpt.ImageDoesNotDependOnSceneScale:Bdpt.LightTracingStartsAtTheNearClipInAWorldVolume"
  SLOW+=":Bdpt.LampsInFrostedGlobesAgreeWithPathTracing:Denoise.LowersTheErrorAgainstAReference"
  SLOW+=":ShadowCatcher.BidirectionalAgreesWithPathTracing:Denoise.KeepsTheMeanWithinTheNoiseAtFullSize"
  SLOW+=":VolPath.MediumOfAnOpaqueBoundaryIsEnteredOnce:Denoise.KeepsTheMeanWithinTheNoiseAtManySamples"
  # The chi-square tests draw a tenth of their samples here (tests/native/chi2.h): the same code
  # runs, the Release suite keeps their statistical power.
  pids=()
  for shard in 0 1; do
    LANTERN_CHI2_SAMPLE_DIVISOR=10 GTEST_TOTAL_SHARDS=2 GTEST_SHARD_INDEX=$shard "$ASAN_DIR/lantern_tests" --gtest_brief=1 \
      --gtest_filter="-$SLOW" >"$ASAN_DIR/asan_shard$shard.log" 2>&1 &
    pids+=($!)
  done
  failed=0
  for shard in 0 1; do
    if ! wait "${pids[$shard]}"; then failed=1; fi
    tail -n 3 "$ASAN_DIR/asan_shard$shard.log"
  done
  if [ $failed -ne 0 ]; then cat "$ASAN_DIR"/asan_shard*.log; echo "native tests under ASan + UBSan failed" >&2; exit 1; fi
  took
fi

if [[ " $STEPS " == *" tsan "* ]]; then
  step "ThreadSanitizer build ($TSAN_DIR)"
  # TBB_USE_PROFILING_TOOLS=2: TBB's headers announce task spawns and waits through ITT, which
  # tests/sanitizers/itt_tsan.c hands to TSan.
  cmake -S . -B "$TSAN_DIR" "${common[@]}" "-DCMAKE_CXX_FLAGS=-fsanitize=thread -DTBB_USE_PROFILING_TOOLS=2" \
    "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=thread" -DLANTERN_BUILD_TESTS=OFF -DLANTERN_BUILD_TSAN=ON >/dev/null
  cmake --build "$TSAN_DIR" -j"$JOBS" --target tsan_render itt_tsan
  took
  step "threaded renders under ThreadSanitizer"
  INTEL_LIBITTNOTIFY64="$ROOT/$TSAN_DIR/tests/sanitizers/libitt_tsan.so" INTEL_ITTNOTIFY_GROUPS=all \
  TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$ROOT/tests/sanitizers/tsan.supp:external_symbolizer_path=$SYMBOLIZER" \
    "$TSAN_DIR/tests/sanitizers/tsan_render"
  took
fi

if [[ " $STEPS " == *" fuzz "* ]]; then
  FUZZ="$ASAN_DIR/tests/fuzz"
  SEEDS="$ASAN_DIR/fuzz/seeds"
  rm -rf "$SEEDS"
  "$FUZZ/make_fuzz_seeds" generated "$SEEDS"
  for target in abi vdb exr image_file; do
    step "fuzzing $target for $FUZZ_SECONDS s"
    bin="$FUZZ/fuzz_$target"
    if [ "$target" = exr ]; then bin="$FUZZ/fuzz_exr_merge"; fi
    corpus="$ASAN_DIR/fuzz/corpus/$target"  # what this machine's runs found (kept between runs)
    mkdir -p "$corpus" "$ASAN_DIR/fuzz/artifacts"
    dirs=("$corpus")
    for d in "tests/fuzz/corpus/$target" "$SEEDS/$target"; do
      if [ -d "$d" ]; then dirs+=("$d"); fi
    done
    # -timeout: one input may take at most 10 s (they take milliseconds); -rss_limit_mb: a crafted
    # input must not make Lantern take more than 2 GB. A failure leaves its input in artifacts/.
    # OpenVDB 10 and OpenEXR 3.1 allocate what a file's length fields say before reading (a few
    # mutated bytes make them allocate and clear gigabytes: docs/testing.md): for the file targets,
    # inputs run in a child process (-fork=1) where such timeouts and out-of-memory ends are
    # counted, not failures; crashes and sanitizer reports still fail the run.
    mode=(); if [ "$target" != abi ]; then mode=(-fork=1 -ignore_timeouts=1 -ignore_ooms=1); fi
    log="$ASAN_DIR/fuzz/$target.log"
    rc=0
    # -seed: a fixed seed makes a fresh machine explore the same inputs first (CI then finds what a
    # local run of the same length finds; LANTERN_FUZZ_SEED=0 draws one).
    "$bin" "${mode[@]}" -seed="${LANTERN_FUZZ_SEED:-1}" -max_total_time="$FUZZ_SECONDS" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$ASAN_DIR/fuzz/artifacts/$target-" "${dirs[@]}" >"$log" 2>&1 || rc=$?
    # In fork mode libFuzzer exits with the code of its last job, also an ignored timeout (70) or
    # out-of-memory end (71): those pass when its last count shows no crash.
    crashes=$(grep -o "oom/timeout/crash: [0-9]*/[0-9]*/[0-9]*" "$log" | tail -n 1 | sed 's|.*/||' || true)
    if [ ${#mode[@]} -gt 0 ] && { [ $rc -eq 70 ] || [ $rc -eq 71 ]; } && [ "${crashes:-1}" = 0 ]; then rc=0; fi
    if [ $rc -ne 0 ]; then
      cat "$log"
      echo "fuzz_$target failed: the input is in $ASAN_DIR/fuzz/artifacts/ (docs/testing.md: make it a test)" >&2
      exit 1
    fi
    grep -E "^#[0-9]+.*(DONE|oom/timeout/crash)|^stat::number_of_executed_units|^stat::peak_rss_mb|^INFO: exiting" "$log" | tail -n 4 || true
    took
  done
fi
echo "sanitizers and fuzzing: all passed"
