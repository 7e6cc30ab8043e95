// ThreadSanitizer's suppressions for a test program that runs Cyclone DDS (linked in by
// symb_test_uses_dds, tests/CMakeLists.txt, under TSan only).
//
// Debian's Cyclone DDS is not built for ThreadSanitizer: its threads hand network buffers to each
// other through its own atomics, which TSan cannot see, so it reports races on those buffers
// between two of Cyclone's threads (its receive thread and its delivery queue, its garbage
// collector and its sender). Only races with Cyclone's socket calls on a stack are suppressed:
// our listeners and streams never touch its buffers, so a race of ours is still reported.
extern "C" const char* __tsan_default_suppressions() { return "race:ddsrt_sendmsg\nrace:ddsrt_recvmsg\n"; }
