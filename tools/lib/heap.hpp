#pragma once
// How the programs that run simulations (the command line, the Python module) set up the C
// library's heap.

namespace palpable::tools {

// Keeps freed heap memory for the next allocation instead of handing it back to the system at
// once. The held contact solve allocates and frees matrices of its island's size at every solve;
// with glibc's default (trim the heap's top once 128 KiB of it is free) each solve shrank the
// heap and the next grew it again, and a pile of 100 balls (tools/stacks/pile.py 100 sphere 0.52)
// spent 11 of its 31 s of CPU in the system, unmapping pages and flushing the TLB. Here the top
// is trimmed only past 64 MiB free, and blocks of up to 32 MiB come from the heap rather than
// from a mapping of their own (that threshold no longer adapts once the trim threshold is set).
// Peak memory is unchanged; what is freed stays with the process. Elsewhere than glibc, nothing.
void keep_freed_heap();

}  // namespace palpable::tools
