// Fast DDS headers must come before Cyclone's q_radmin.h (its PID_* macros clash).
#include <fastdds/dds/topic/TopicDataType.hpp>

#include "cyclone_sertype.h"

#include <algorithm>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>
#include <dds/ddsi/q_radmin.h>
#include <dds/ddsrt/mh3.h>

namespace auv::interfaces::detail {
namespace {

using eprosima::fastdds::dds::TopicDataType;
using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::SerializedPayload_t;

struct Sertype : ddsi_sertype {
  std::unique_ptr<TopicDataType> topic_type;
  msg::TypeSupport support;
  std::mutex key_mutex;  // TopicDataType::getKey uses a shared buffer
};

struct Serdata : ddsi_serdata {
  std::unique_ptr<unsigned char[]> cdr;     // encapsulation header + XCDR1 body, padded to 4 bytes
  uint32_t size = 0;                        // serialized size without the padding
  std::array<unsigned char, 16> key{};      // keyhash as computed without forcing MD5
  std::array<unsigned char, 16> key_md5{};  // keyhash with MD5 forced
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
  d->cdr.reset(new unsigned char[padded]);
  std::memset(d->cdr.get() + size, 0, padded - size);
  d->size = static_cast<uint32_t>(size);
}

void computeKey(const ddsi_sertype* type, const void* sample, Serdata* d) {
  Sertype* st = mutableSertype(type);
  if (!st->support.keyed) {
    d->hash = type->serdata_basehash;
    return;
  }
  std::lock_guard<std::mutex> lock(st->key_mutex);
  InstanceHandle_t handle;
  st->topic_type->getKey(const_cast<void*>(sample), &handle, false);
  std::memcpy(d->key.data(), handle.value, 16);
  st->topic_type->getKey(const_cast<void*>(sample), &handle, true);
  std::memcpy(d->key_md5.data(), handle.value, 16);
  d->hash = ddsrt_mh3(d->key.data(), d->key.size(), type->serdata_basehash);
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
    if (!ok) {  // malformed: drop it rather than hand garbage to the application
      delete d;
      return nullptr;
    }
    computeKey(type, sample.get(), d);
  } else {
    d->hash = type->serdata_basehash;
  }
  return d;
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
  return d;
}

ddsi_serdata* fromSample(const ddsi_sertype* type, ddsi_serdata_kind kind, const void* sample) {
  const Sertype* st = sertypeOf(type);
  void* data = const_cast<void*>(sample);
  const uint32_t max_size = st->topic_type->getSerializedSizeProvider(data)();
  Serdata* d = newSerdata(type, kind);
  allocate(d, max_size);
  BorrowedPayload payload(d->cdr.get(), 0);
  payload.max_size = max_size;
  if (!st->topic_type->serialize(data, &payload)) {
    delete d;
    return nullptr;
  }
  // Normally exactly max_size; if less, zero the tail so the padding stays zero.
  std::memset(d->cdr.get() + payload.length, 0, max_size - payload.length);
  d->size = payload.length;
  computeKey(type, sample, d);
  return d;
}

void toSer(const ddsi_serdata* dcmn, size_t off, size_t sz, void* buf) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  std::memcpy(buf, d->cdr.get() + off, sz);
}

ddsi_serdata* toSerRef(const ddsi_serdata* dcmn, size_t off, size_t sz, ddsrt_iovec_t* ref) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  ref->iov_base = d->cdr.get() + off;
  ref->iov_len = static_cast<ddsrt_iov_len_t>(sz);
  return ddsi_serdata_ref(dcmn);
}

void toSerUnref(ddsi_serdata* d, const ddsrt_iovec_t*) { ddsi_serdata_unref(d); }

bool toSample(const ddsi_serdata* dcmn, void* sample, void**, void*) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  if (d->kind != SDK_DATA || d->size == 0) return false;
  BorrowedPayload payload(d->cdr.get(), d->size);
  try {
    return sertypeOf(d->type)->topic_type->deserialize(&payload, sample);
  } catch (...) {
    return false;  // malformed data: reported as a failed take, never a crash
  }
}

ddsi_serdata* toUntyped(const ddsi_serdata* dcmn) {
  const auto* d = static_cast<const Serdata*>(dcmn);
  auto* u = new Serdata();
  ddsi_serdata_init(u, d->type, SDK_KEY);
  u->type = nullptr;  // untyped: may outlive the sertype (tkmap)
  u->key = d->key;
  u->key_md5 = d->key_md5;
  u->hash = d->hash;
  return u;
}

bool untypedToSample(const ddsi_sertype*, const ddsi_serdata*, void*, void**, void*) {
  return true;  // only key fields would be filled; invalid samples are skipped by our readers
}

bool eqkey(const ddsi_serdata* a, const ddsi_serdata* b) {
  return static_cast<const Serdata*>(a)->key == static_cast<const Serdata*>(b)->key;
}

uint32_t getSize(const ddsi_serdata* d) { return static_cast<const Serdata*>(d)->size; }

void freeSerdata(ddsi_serdata* d) { delete static_cast<Serdata*>(d); }

size_t print(const ddsi_sertype* type, const ddsi_serdata* d, char* buf, size_t size) {
  return static_cast<size_t>(snprintf(buf, size, "%s(%u bytes)", type ? type->type_name : "?",
                                      static_cast<const Serdata*>(d)->size));
}

void getKeyhash(const ddsi_serdata* dcmn, ddsi_keyhash* buf, bool force_md5) {
  const auto* d = static_cast<const Serdata*>(dcmn);
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

void freeSertype(ddsi_sertype* type) {
  ddsi_sertype_fini(type);
  delete static_cast<Sertype*>(type);
}

void zeroSamples(const ddsi_sertype*, void*, size_t) {}

// Our readers always pass their own sample buffers, so Cyclone never needs to allocate
// C++ samples (loans are not used); these keep the contract for completeness.
void reallocSamples(void** ptrs, const ddsi_sertype* type, void*, size_t oldcount, size_t count) {
  for (size_t i = oldcount; i < count; ++i) ptrs[i] = sertypeOf(type)->topic_type->createData();
}

void freeSamples(const ddsi_sertype* type, void** ptrs, size_t count, dds_free_op_t op) {
  if ((op & DDS_FREE_ALL_BIT) == 0) return;
  for (size_t i = 0; i < count; ++i) sertypeOf(type)->topic_type->deleteData(ptrs[i]);
}

bool equal(const ddsi_sertype* a, const ddsi_sertype* b) {
  return std::strcmp(a->type_name, b->type_name) == 0;
}

uint32_t hash(const ddsi_sertype* type) {
  return ddsrt_mh3(type->type_name, std::strlen(type->type_name), 0);
}

const ddsi_sertype_ops kSertypeOps = {
    ddsi_sertype_v0, nullptr, &freeSertype, &zeroSamples, &reallocSamples, &freeSamples, &equal,
    &hash,           nullptr, nullptr,      nullptr,      nullptr,         nullptr,      nullptr,
};

}  // namespace

ddsi_sertype* createSertype(const msg::TypeSupport& type) {
  auto* st = new Sertype();
  st->support = type;
  st->topic_type.reset(type.make_topic_data_type());
  ddsi_sertype_init(st, type.name.c_str(), &kSertypeOps, &kSerdataOps, !type.keyed);
  st->allowed_data_representation = DDS_DATA_REPRESENTATION_FLAG_XCDR1;
  return st;
}

}  // namespace auv::interfaces::detail
