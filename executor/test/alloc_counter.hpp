// Counting the heap allocations of the calling thread (alloc_counter.cpp replaces the global operator new).
// Functions rather than extern thread_local variables: GCC 12 with -fsanitize=undefined miscompiles the null
// check of an extern thread_local's address (it tests the flags of an unrelated comparison) and reports a
// store to a null pointer.
#pragma once

/// Resets this thread's count and starts counting.
void start_counting_allocations();
/// Stops counting on this thread; returns the allocations since start_counting_allocations().
long stop_counting_allocations();
