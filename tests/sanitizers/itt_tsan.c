/* A tool library for TBB's ITT notifications that hands them to ThreadSanitizer.
 *
 * libtbb is not built with TSan, so the synchronisation inside it (task spawning and stealing,
 * waiting for a parallel_for) is invisible, and every access of one pass's data by another
 * thread in the next would be reported as a race. TBB announces that synchronisation through
 * Intel's ITT API (the hooks Intel Inspector, itself a race detector, relies on): it calls
 * __itt_sync_releasing(p) before it publishes something and __itt_sync_acquired(p) after it has
 * taken it. TBB loads this library when INTEL_LIBITTNOTIFY64 names it and INTEL_ITTNOTIFY_GROUPS
 * enables the sync group (scripts/run_sanitizers.sh sets both); the header-level notifications
 * (task spawn, wait_context) also need the code built with TBB_USE_PROFILING_TOOLS=2. */
void __tsan_acquire(void* addr);
void __tsan_release(void* addr);

/* Its presence selects ITT's current (not legacy) function names. */
void __itt_api_version(void) {}
void __itt_sync_acquired(void* addr) { __tsan_acquire(addr); }
void __itt_sync_releasing(void* addr) { __tsan_release(addr); }
