// MessageIterator: a k-way merge of chunks in log-time order. Sources (chunks, and the
// messages outside chunks) are taken in order of their first log time; a source is read only
// when the earliest message still waiting is not before its first time, so chunks that do not
// overlap are read one at a time and overlapping ones are merged.

#include <algorithm>
#include <set>

#include "auv/bag/mcap_reader.h"

namespace auv::bag {

MessageIterator::MessageIterator(McapReader& reader, ReadFilter filter)
    : reader_(&reader), filter_(std::move(filter)) {
  std::set<uint16_t> wanted_ids;
  for (const auto& [id, channel] : reader.channels_) {
    if (wanted(id)) wanted_ids.insert(id);
  }
  for (size_t i = 0; i < reader.chunks_.size(); ++i) {
    const ChunkIndex& chunk = reader.chunks_[i];
    if (reader.chunk_states_[i] == McapReader::ChunkState::DAMAGED) continue;
    if (chunk.message_end_time < filter_.start_ns || chunk.message_start_time > filter_.end_ns) {
      continue;
    }
    if (!filter_.topics.empty() && !chunk.message_index_offsets.empty()) {
      // The summary says which channels a chunk has: skip those with none of ours.
      bool any = false;
      for (const auto& [channel, offset] : chunk.message_index_offsets) {
        any = any || wanted_ids.count(channel) > 0;
      }
      if (!any) continue;
    }
    sources_.push_back(Source{chunk.message_start_time, chunk.chunk_start_offset, int(i)});
  }
  if (!reader.loose_.empty()) {
    uint64_t first = UINT64_MAX;
    for (const Entry& entry : reader.loose_) first = std::min(first, entry.log_time);
    sources_.push_back(Source{first, reader.loose_.front().offset, -1});
  }
  std::sort(sources_.begin(), sources_.end(), [](const Source& a, const Source& b) {
    return a.start_time != b.start_time ? a.start_time < b.start_time : a.order < b.order;
  });
}

bool MessageIterator::wanted(uint16_t channel_id) const {
  if (filter_.topics.empty()) return true;
  const auto channel = reader_->channels_.find(channel_id);
  return channel != reader_->channels_.end() &&
         std::find(filter_.topics.begin(), filter_.topics.end(), channel->second.topic) !=
             filter_.topics.end();
}

void MessageIterator::load(const Source& source) {
  Cursor cursor;
  cursor.order = source.order;
  const std::vector<Entry>* entries = &reader_->loose_;
  std::optional<McapReader::LoadedChunk> loaded;
  if (source.chunk >= 0) {
    loaded = reader_->loadChunk(static_cast<size_t>(source.chunk));
    if (!loaded) return;  // damaged: the reader has said why
    cursor.records = loaded->records;
    cursor.chunk_offset = reader_->chunks_[static_cast<size_t>(source.chunk)].chunk_start_offset;
    entries = &loaded->entries;
  }
  for (const Entry& entry : *entries) {
    if (entry.log_time >= filter_.start_ns && entry.log_time <= filter_.end_ns &&
        wanted(entry.channel_id)) {
      cursor.entries.push_back(entry);
    }
  }
  if (cursor.entries.empty()) return;
  std::stable_sort(cursor.entries.begin(), cursor.entries.end(),
                   [](const Entry& a, const Entry& b) { return a.log_time < b.log_time; });
  cursors_.push_back(std::move(cursor));
  heap_.push_back(cursors_.size() - 1);
  std::push_heap(heap_.begin(), heap_.end(), [this](size_t a, size_t b) { return later(a, b); });
}

bool MessageIterator::later(size_t a, size_t b) const {
  const Cursor& x = cursors_[a];
  const Cursor& y = cursors_[b];
  const uint64_t tx = x.entries[x.next].log_time;
  const uint64_t ty = y.entries[y.next].log_time;
  if (tx != ty) return tx > ty;
  return x.order > y.order;  // equal times: file order
}

std::optional<BagMessage> MessageIterator::next() {
  const auto heap_order = [this](size_t a, size_t b) { return later(a, b); };
  while (next_source_ < sources_.size()) {
    if (!heap_.empty()) {
      const Cursor& top = cursors_[heap_.front()];
      if (sources_[next_source_].start_time > top.entries[top.next].log_time) break;
    }
    load(sources_[next_source_++]);
  }
  if (heap_.empty()) return std::nullopt;

  std::pop_heap(heap_.begin(), heap_.end(), heap_order);
  const size_t index = heap_.back();
  Cursor& cursor = cursors_[index];
  const Entry entry = cursor.entries[cursor.next++];
  BagMessage out;
  if (cursor.records) {
    out.message = parseMessage(cursor.records->data() + entry.offset, entry.size);
  } else {
    const std::vector<uint8_t> bytes = reader_->readAt(entry.offset, entry.size);
    out.message = parseMessage(bytes.data(), bytes.size());
  }
  out.chunk_offset = cursor.chunk_offset;
  out.channel = &reader_->channels_.at(entry.channel_id);
  const auto schema = reader_->schemas_.find(out.channel->schema_id);
  if (schema != reader_->schemas_.end()) out.schema = &schema->second;

  if (cursor.next < cursor.entries.size()) {
    std::push_heap(heap_.begin(), heap_.end(), heap_order);
  } else {
    heap_.pop_back();
    cursor = Cursor{};  // frees the chunk's records
  }
  return out;
}

}  // namespace auv::bag
