// Replacement allocation functions for the benchmark binary (see alloc_count.hpp). glibc
// documents replacing malloc in the main program ("Replacing malloc" in its manual): malloc,
// free, calloc and realloc must all be replaced together; the aligned variants are replaced
// too so that every way of allocating is counted. Each forwards to glibc's own allocator
// (__libc_malloc and friends, exported for this purpose), so memory from any of them can be
// freed by any free().
#include "bench/alloc_count.hpp"

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <new>

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t n, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* p);
}

namespace {

std::atomic<bool> g_active{false};
std::atomic<long> g_count{0};

inline void note() {
  if (g_active.load(std::memory_order_relaxed)) g_count.fetch_add(1, std::memory_order_relaxed);
}

void* aligned(std::size_t alignment, std::size_t size) {
  note();
  return __libc_memalign(alignment, size);
}

void* new_or_throw(std::size_t size) {
  note();
  void* p = __libc_malloc(size == 0 ? 1 : size);
  if (!p) throw std::bad_alloc();
  return p;
}

void* new_aligned_or_throw(std::size_t size, std::align_val_t al) {
  note();
  void* p = __libc_memalign(static_cast<std::size_t>(al), size == 0 ? 1 : size);
  if (!p) throw std::bad_alloc();
  return p;
}

}  // namespace

namespace stiffbench::bench {

void alloc_count_start() {
  g_count.store(0, std::memory_order_relaxed);
  g_active.store(true, std::memory_order_seq_cst);
}

long alloc_count_stop() {
  g_active.store(false, std::memory_order_seq_cst);
  return g_count.load(std::memory_order_relaxed);
}

}  // namespace stiffbench::bench

extern "C" {

void* malloc(std::size_t size) {
  note();
  return __libc_malloc(size);
}

void free(void* p) { __libc_free(p); }

void* calloc(std::size_t n, std::size_t size) {
  note();
  return __libc_calloc(n, size);
}

void* realloc(void* p, std::size_t size) {
  note();
  return __libc_realloc(p, size);
}

void* memalign(std::size_t alignment, std::size_t size) { return aligned(alignment, size); }

void* aligned_alloc(std::size_t alignment, std::size_t size) { return aligned(alignment, size); }

int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0) return EINVAL;
  void* p = aligned(alignment, size);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}

}  // extern "C"

void* operator new(std::size_t size) { return new_or_throw(size); }
void* operator new[](std::size_t size) { return new_or_throw(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  note();
  return __libc_malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  note();
  return __libc_malloc(size == 0 ? 1 : size);
}
void* operator new(std::size_t size, std::align_val_t al) { return new_aligned_or_throw(size, al); }
void* operator new[](std::size_t size, std::align_val_t al) {
  return new_aligned_or_throw(size, al);
}
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
