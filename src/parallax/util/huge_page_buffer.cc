#include "parallax/util/huge_page_buffer.h"

#include <algorithm>
#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace parallax {
namespace {

constexpr size_t kHugePageSize = size_t{2} << 20;

}  // namespace

HugePageBuffer::~HugePageBuffer() { std::free(data_); }

void* HugePageBuffer::Reserve(size_t bytes) {
  if (bytes <= capacity_ && data_ != nullptr) return data_;
  std::free(data_);
  data_ = nullptr;
  capacity_ = 0;
  // aligned_alloc wants a multiple of the alignment.
  const size_t rounded =
      (std::max<size_t>(bytes, 1) + kHugePageSize - 1) / kHugePageSize * kHugePageSize;
  data_ = std::aligned_alloc(kHugePageSize, rounded);
  if (data_ == nullptr) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // Advice only: where the kernel has huge pages off, this fails and 4 KiB pages serve.
  madvise(data_, rounded, MADV_HUGEPAGE);
#endif
  capacity_ = rounded;
  return data_;
}

}  // namespace parallax
