// Fast DDS headers must come before Cyclone's q_radmin.h (its PID_* macros clash).
#include <fastdds/dds/topic/TopicDataType.hpp>

#include "cyclone_sertype.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <string>

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>
#include <dds/ddsi/q_protocol.h>
#include <dds/ddsi/q_radmin.h>
#include <dds/ddsrt/mh3.h>
#include <dds/ddsrt/time.h>

#include "serialized_sample.h"

namespace auv::interfaces::detail {
namespace {

// Cyclone hands serdata and sertypes between its threads through atomics and lock-free queues
// inside the uninstrumented library, which ThreadSanitizer cannot see: it took the next
// thread's access (a decode, a free) for a race. Under TSan each op announces the hand-over
// itself — the object released when made, acquired and released around every use, acquired
// before it is freed; elsewhere these are nothing (docs/reliability.md, "Sanitizers").
#if defined(__SANITIZE_THREAD__)
#define AUV_THREAD_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define AUV_THREAD_SANITIZER 1
#endif
#endif
#ifdef AUV_THREAD_SANITIZER
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
extern "C" void AnnotateIgnoreWritesBegin(const char* file, int line);
extern "C" void AnnotateIgnoreWritesEnd(const char* file, int line);
void acquired(const void* object) { __tsan_acquire(const_cast<void*>(object)); }
void released(const void* object) { __tsan_release(const_cast<void*>(object)); }
void ignoreWritesBegin() { AnnotateIgnoreWritesBegin(__FILE__, __LINE__); }
void ignoreWritesEnd() { AnnotateIgnoreWritesEnd(__FILE__, __LINE__); }
#else
void acquired(const void*) {}
void released(const void*) {}
void ignoreWritesBegin() {}
void ignoreWritesEnd() {}
#endif

/// Around one use of an object Cyclone may have handed over from another thread.
class HandOver {
 public:
  explicit HandOver(const void* object) : object_(object) { acquired(object_); }
  ~HandOver() { released(object_); }
  HandOver(const HandOver&) = delete;
  HandOver& operator=(const HandOver&) = delete;

 private:
  const void* object_;
};

template <class T>
T* handedOver(T* object) {
  if (object != nullptr) released(object);
  return object;
}

using eprosima::fastdds::dds::TopicDataType;
using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::SerializedPayload_t;

struct Sertype : ddsi_sertype {
  std::unique_ptr<TopicDataType> topic_type;
  msg::TypeSupport support;
  bool serialized = false;  // samples are RawSamples (kRawSerdataOps)
  std::mutex key_mutex;     // TopicDataType::getKey uses a shared buffer
};

struct FreeBytes {
  void operator()(unsigned char* p) const { std::free(p); }
};
using Bytes = std::unique_ptr<unsigned char[], FreeBytes>;  // malloc'ed: see allocate*

struct Serdata : ddsi_serdata {
  Bytes cdr;                                // encapsulation header + XCDR1 body, padded to 4 bytes
  uint32_t size = 0;                        // serialized size without the padding
  std::array<unsigned char, 16> key{};      // keyhash as computed without forcing MD5
  std::array<unsigned char, 16> key_md5{};  // keyhash with MD5 forced
  int64_t reception_ns = 0;                 // serialized sertype only: when it arrived
  int64_t sequence = -1;                    // serialized sertype only: the writer's, if known
};

const Sertype* sertypeOf(const ddsi_sertype* type) { return static_cast<const Sertype*>(type); }
Sertype* mutableSertype(const ddsi_sertype* type) {
  return const_cast<Sertype*>(static_cast<const Sertype*>(type));
}

// A SerializedPayload_t that only borrows memory (its destructor would free `data`).
struct BorrowedPayload : SerializedPayload_t {
  BorrowedPayload(unsigned char* bytes, uint32_t length) {
    data = bytes;
    this->length = length;
    max_size = length;
  }
  ~BorrowedPayload() { data = nullptr; }
};

extern const ddsi_serdata_ops kSerdataOps;

Serdata* newSerdata(const ddsi_sertype* type, ddsi_serdata_kind kind) {
  auto* d = new Serdata();
  ddsi_serdata_init(d, type, kind);
  return d;
}

// Room for `size` bytes rounded up to 4, left uninitialised: the caller writes every byte
// up to `size` right after, so large payloads get no zero-fill pass (a std::vector resize
// would add one, and a second allocation and copy when padding afterwards). Only the
// padding is zeroed.
void allocate(Serdata* d, size_t size) {
  const size_t padded = (size + 3) & ~size_t(3);
  d->cdr = Bytes(static_cast<unsigned char*>(std::malloc(padded)));
  if (!d->cdr) throw std::bad_alloc();
  std::memset(d->cdr.get() + size, 0, padded - size);
  d->size = static_cast<uint32_t>(size);
}

// The same, all zeroed, for serializing a sample: fastcdr skips alignment padding without
// writing it, which would otherwise send uninitialised heap bytes. Measured: no cost up to
// 1 MiB, 74 us per 4 MiB sample (~2 % of its latency, docs/architecture.md).
void allocateZeroed(Serdata* d, size_t size) {
  const size_t padded = (size + 3) & ~size_t(3);
  d->cdr = Bytes(static_cast<unsigned char*>(std::calloc(padded, 1)));
  if (!d->cdr) throw std::bad_alloc();
  d->size = static_cast<uint32_t>(size);
}

// False when the sample has no key to compute (a @key string over its 255-byte bound, as
// malformed or foreign data may have: GuardedPubSubType::getKey answers false).
bool computeKey(const ddsi_sertype* type, const void* sample, Serdata* d) {
  Sertype* st = mutableSertype(type);
  if (!st->support.keyed) {
    d->hash = type->serdata_basehash;
    return true;
  }
  std::lock_guard<std::mutex> lock(st->key_mutex);
  InstanceHandle_t handle;
  if (!st->topic_type->getKey(const_cast<void*>(sample), &handle, false)) return false;
  std::memcpy(d->key.data(), handle.value, 16);
  if (!st->topic_type->getKey(const_cast<void*>(sample), &handle, true)) return false;
  std::memcpy(d->key_md5.data(), handle.value, 16);
  d->hash = ddsrt_mh3(d->key.data(), d->key.size(), type->serdata_basehash);
  return true;
}

// Received bytes: keep them; keyed types are deserialized once to find their key.
Serdata* finishFromSer(const ddsi_sertype* type, Serdata* d) {
  if (sertypeOf(type)->support.keyed) {
    auto sample = sertypeOf(type)->support.create_sample();
    BorrowedPayload payload(d->cdr.get(), d->size);
    bool ok = false;
    try {
      ok = sertypeOf(type)->topic_type->deserialize(&payload, sample.get());
    } catch (...) {
    }
    // Malformed, or a key it cannot have: dropped rather than handed to the application.
    if (!ok || !computeKey(type, sample.get(), d)) {
      delete d;
      return nullptr;
    }
  } else {
    d->hash = type->serdata_basehash;
  }
  return handedOver(d);
}

ddsi_serdata* fromSer(const ddsi_sertype* type, ddsi_serdata_kind kind, const nn_rdata* fragchain,
                      size_t size) {
  Serdata* d = newSerdata(type, kind);
  allocate(d, size);
  uint32_t off = 0;
  for (; fragchain != nullptr; fragchain = fragchain->nextfrag) {
    if (fragchain->maxp1 > off) {
      const unsigned char* payload =
          NN_RMSG_PAYLOADOFF(fragchain->rmsg, NN_RDATA_PAYLOAD_OFF(fragchain));
      const uint32_t end = std::min<uint32_t>(fragchain->maxp1, static_cast<uint32_t>(size));
      if (end > off) std::memcpy(d->cdr.get() + off, payload + (off - fragchain->min), end - off);
      off = fragchain->maxp1;
    }
  }
  if (off < size) std::memset(d->cdr.get() + off, 0, size - off);  // never for a whole sample
  return finishFromSer(type, d);
}

ddsi_serdata* fromSerIov(const ddsi_sertype* type, ddsi_serdata_kind kind, ddsrt_msg_iovlen_t niov,
                         const ddsrt_iovec_t* iov, size_t size) {
  Serdata* d = newSerdata(type, kind);
  allocate(d, size);
  size_t off = 0;
  for (ddsrt_msg_iovlen_t i = 0; i < niov && off < size; ++i) {
    const size_t n = std::min<size_t>(iov[i].iov_len, size - off);
    std::memcpy(d->cdr.get() + off, iov[i].iov_base, n);
    off += n;
  }
  std::memset(d->cdr.get() + off, 0, size - off);  // only if the iovecs were short
  return finishFromSer(type, d);
}

ddsi_serdata* fromKeyhash(const ddsi_sertype* type, const ddsi_keyhash* keyhash) {
  Serdata* d = newSerdata(type, SDK_KEY);
  std::memcpy(d->key.data(), keyhash->value, 16);
  d->key_md5 = d->key;
  d->hash = ddsrt_mh3(d->key.data(), d->key.size(), type->serdata_basehash);
  return handedOver(d);
}

ddsi_serdata* fromSample(const ddsi_sertype* type, ddsi_serdata_kind kind, const void* sample) {
  const Sertype* st = sertypeOf(type);
  void* data = const_cast<void*>(sample);
  const uint32_t max_size = st->topic_type->getSerializedSizeProvider(data)();
  Serdata* d = newSerdata(type, kind);
  allocateZeroed(d, max_size);
  BorrowedPayload payload(d->cdr.get(), 0);
  payload.max_size = max_size;
  if (!st->topic_type->serialize(data, &payload)) {
    delete d;
    return nullptr;
  }
  d->size = payload.length;  // normally exactly max_size; the rest stays zero
  // A key the type cannot compute: dds_write fails (the backend throws) instead.
  if (!computeKey(type, sample, d)) {
    delete d;
    return nullptr;
  }
  return handedOver(d);
}

void toSer(const ddsi_serdata* dcmn, size_t off, size_t sz, void* buf) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  const HandOver use(d);
  std::memcpy(buf, d->cdr.get() + off, sz);
}

ddsi_serdata* toSerRef(const ddsi_serdata* dcmn, size_t off, size_t sz, ddsrt_iovec_t* ref) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  const HandOver use(d);
  ref->iov_base = d->cdr.get() + off;
  ref->iov_len = static_cast<ddsrt_iov_len_t>(sz);
  return ddsi_serdata_ref(dcmn);
}

// Cyclone has read the bytes toSerRef lent it (sendmsg): that use ends here. The reference
// count's decrement is inlined here from Cyclone's header, while the last one may come from
// inside the library, whose atomics TSan does not see: our write to the count is not its to
// judge.
void toSerUnref(ddsi_serdata* d, const ddsrt_iovec_t*) {
  released(d);
  ignoreWritesBegin();
  ddsi_serdata_unref(d);
  ignoreWritesEnd();
}

// Set by a failed to_sample on the thread that takes (Cyclone converts inside dds_take).
thread_local bool t_take_failed = false;

bool failed() {
  t_take_failed = true;
  return false;
}

bool toSample(const ddsi_serdata* dcmn, void* sample, void**, void*) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  const HandOver use(d);
  if (d->kind != SDK_DATA || d->size == 0) return failed();
  BorrowedPayload payload(d->cdr.get(), d->size);
  try {
    if (sertypeOf(d->type)->topic_type->deserialize(&payload, sample)) return true;
  } catch (...) {
  }
  return failed();  // malformed data: dropped by the reader (takeFailed), never a crash
}

ddsi_serdata* toUntyped(const ddsi_serdata* dcmn) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  const HandOver use(d);
  auto* u = new Serdata();
  ddsi_serdata_init(u, d->type, SDK_KEY);
  u->type = nullptr;  // untyped: may outlive the sertype (tkmap)
  u->key = d->key;
  u->key_md5 = d->key_md5;
  u->hash = d->hash;
  return handedOver(u);
}

bool untypedToSample(const ddsi_sertype*, const ddsi_serdata*, void*, void**, void*) {
  return true;  // only key fields would be filled; invalid samples are skipped by our readers
}

bool eqkey(const ddsi_serdata* a, const ddsi_serdata* b) {
  const HandOver use_a(a), use_b(b);
  return static_cast<const Serdata*>(a)->key == static_cast<const Serdata*>(b)->key;
}

uint32_t getSize(const ddsi_serdata* d) {
  const HandOver use(d);
  return static_cast<const Serdata*>(d)->size;
}

void freeSerdata(ddsi_serdata* d) {
  acquired(d);
  delete static_cast<Serdata*>(d);
}

size_t print(const ddsi_sertype* type, const ddsi_serdata* d, char* buf, size_t size) {
  const HandOver use(d);
  return static_cast<size_t>(snprintf(buf, size, "%s(%u bytes)", type ? type->type_name : "?",
                                      static_cast<const Serdata*>(d)->size));
}

void getKeyhash(const ddsi_serdata* dcmn, ddsi_keyhash* buf, bool force_md5) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  const HandOver use(d);
  std::memcpy(buf->value, force_md5 ? d->key_md5.data() : d->key.data(), 16);
}

const ddsi_serdata_ops kSerdataOps = {
    &eqkey,      &getSize,         &fromSer,     &fromSerIov, &fromKeyhash,
    &fromSample, &toSer,           &toSerRef,    &toSerUnref, &toSample,
    &toUntyped,  &untypedToSample, &freeSerdata, &print,      &getKeyhash,
#ifdef DDS_HAS_SHM
    nullptr,     nullptr,
#endif
};

// The serialized sertype: the same serdata, moved to and from RawSamples as bytes.

// The writer's sequence number, from the DATA or DATA_FRAG submessage the first fragment came
// in (Cyclone has byte-swapped its header fields to native order while validating it).
int64_t sequenceOf(const nn_rdata* fragchain) {
  if (fragchain == nullptr || fragchain->rmsg == nullptr) return -1;
  const auto* common = reinterpret_cast<const Data_DataFrag_common_t*>(
      NN_RMSG_PAYLOADOFF(fragchain->rmsg, NN_RDATA_SUBMSG_OFF(fragchain)));
  const unsigned id = common->smhdr.submessageId;
  if (id != SMID_DATA && id != SMID_DATA_FRAG) return -1;
  return (static_cast<int64_t>(common->writerSN.high) << 32) | common->writerSN.low;
}

ddsi_serdata* rawFromSer(const ddsi_sertype* type, ddsi_serdata_kind kind,
                         const nn_rdata* fragchain, size_t size) {
  auto* d = static_cast<Serdata*>(fromSer(type, kind, fragchain, size));
  if (d != nullptr) {
    const HandOver use(d);
    d->reception_ns = dds_time();
    d->sequence = sequenceOf(fragchain);
  }
  return d;
}

// From a writer in this process (local delivery converts its serdata through the bytes).
ddsi_serdata* rawFromSerIov(const ddsi_sertype* type, ddsi_serdata_kind kind,
                            ddsrt_msg_iovlen_t niov, const ddsrt_iovec_t* iov, size_t size) {
  auto* d = static_cast<Serdata*>(fromSerIov(type, kind, niov, iov, size));
  if (d != nullptr) {
    const HandOver use(d);
    d->reception_ns = dds_time();
  }
  return d;
}

ddsi_serdata* rawFromSample(const ddsi_sertype* type, ddsi_serdata_kind kind, const void* sample) {
  const auto* raw = static_cast<const RawSample*>(sample);
  Serdata* d = newSerdata(type, kind);
  allocate(d, raw->size());
  std::memcpy(d->cdr.get(), raw->data(), raw->size());
  return finishFromSer(type, d);  // keyed: decoded for the key, nullptr if it does not decode
}

bool rawToSample(const ddsi_serdata* dcmn, void* sample, void**, void*) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  const HandOver use(d);
  if (d->kind != SDK_DATA || d->size == 0) return failed();
  auto* raw = static_cast<RawSample*>(sample);
  raw->view = nullptr;
  raw->bytes.assign(d->cdr.get(), d->cdr.get() + d->size);
  raw->reception_timestamp_ns = d->reception_ns;
  raw->sequence_number = d->sequence;
  return true;
}

const ddsi_serdata_ops kRawSerdataOps = {
    &eqkey,         &getSize,         &rawFromSer,  &rawFromSerIov, &fromKeyhash,
    &rawFromSample, &toSer,           &toSerRef,    &toSerUnref,    &rawToSample,
    &toUntyped,     &untypedToSample, &freeSerdata, &print,         &getKeyhash,
#ifdef DDS_HAS_SHM
    nullptr,        nullptr,
#endif
};

void freeSertype(ddsi_sertype* type) {
  acquired(type);
  ddsi_sertype_fini(type);
  delete static_cast<Sertype*>(type);
}

void zeroSamples(const ddsi_sertype*, void*, size_t) {}

// Our readers always pass their own sample buffers, so Cyclone never needs to allocate
// C++ samples (loans are not used); these keep the contract for completeness.
void reallocSamples(void** ptrs, const ddsi_sertype* type, void*, size_t oldcount, size_t count) {
  const Sertype* st = sertypeOf(type);
  for (size_t i = oldcount; i < count; ++i)
    ptrs[i] = st->serialized ? new RawSample() : st->topic_type->createData();
}

void freeSamples(const ddsi_sertype* type, void** ptrs, size_t count, dds_free_op_t op) {
  if ((op & DDS_FREE_ALL_BIT) == 0) return;
  const Sertype* st = sertypeOf(type);
  for (size_t i = 0; i < count; ++i) {
    if (st->serialized)
      delete static_cast<RawSample*>(ptrs[i]);
    else
      st->topic_type->deleteData(ptrs[i]);
  }
}

bool equal(const ddsi_sertype* a, const ddsi_sertype* b) {
  const HandOver use_a(a), use_b(b);
  return std::strcmp(a->type_name, b->type_name) == 0;
}

uint32_t hash(const ddsi_sertype* type) {
  const HandOver use(type);
  return ddsrt_mh3(type->type_name, std::strlen(type->type_name), 0);
}

const ddsi_sertype_ops kSertypeOps = {
    ddsi_sertype_v0, nullptr, &freeSertype, &zeroSamples, &reallocSamples, &freeSamples, &equal,
    &hash,           nullptr, nullptr,      nullptr,      nullptr,         nullptr,      nullptr,
};

}  // namespace

bool takeFailed() {
  const bool was = t_take_failed;
  t_take_failed = false;
  return was;
}

ddsi_sertype* createSertype(const msg::TypeSupport& type, bool serialized) {
  auto* st = new Sertype();
  st->support = type;
  st->serialized = serialized;
  st->topic_type.reset(type.make_topic_data_type());
  // Distinct serdata ops also keep the two kinds of one type name apart in Cyclone's sertype
  // registry (ddsi_sertype_equal compares them).
  ddsi_sertype_init(st, type.name.c_str(), &kSertypeOps,
                    serialized ? &kRawSerdataOps : &kSerdataOps, !type.keyed);
  st->allowed_data_representation = DDS_DATA_REPRESENTATION_FLAG_XCDR1;
  return handedOver(st);
}

}  // namespace auv::interfaces::detail
