// Linked into fuzz_vdb only (not into the test suite): operator new fails with std::bad_alloc for requests
// above 256 MiB, as it does in a release build under a memory limit (`ulimit -v`).
//
// Why: OpenVDB 10 trusts the sizes in a file (a compressed chunk's byte count in bloscFromStream and
// zipFromStream, a string's length in GridDescriptor::read and MetaMap::readMeta) and allocates -- for
// strings also fills -- them before reading. In a release build a corrupt size of terabytes throws
// std::bad_alloc, which read_vdb_file reports as "not a readable OpenVDB file"; under AddressSanitizer the
// same request aborts the process, and sizes of a few GiB exceed -rss_limit_mb, so that every corrupt size
// field would end the run. The cap also covers read_vdb_file's own dense grid (at most 2^28 floats, 1 GiB),
// which then fails the same way.
#include <cstdlib>
#include <new>

namespace {

constexpr std::size_t AllocationLimit = std::size_t(256) << 20;

void* allocate(std::size_t size) {
    if (size > AllocationLimit) throw std::bad_alloc();
    if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
    throw std::bad_alloc();
}

void* allocate_nothrow(std::size_t size) noexcept {
    return size > AllocationLimit ? nullptr : std::malloc(size == 0 ? 1 : size);
}

} // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return allocate_nothrow(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return allocate_nothrow(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
