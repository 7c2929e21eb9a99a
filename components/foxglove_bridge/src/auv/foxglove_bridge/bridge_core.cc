#include "auv/foxglove_bridge/bridge_core.h"

#include <chrono>

namespace auv::foxglove_bridge {

BridgeCore::BridgeCore(CoreOptions options, Transport& transport, Listener& listener)
    : options_(std::move(options)), transport_(transport), listener_(listener) {}

uint32_t BridgeCore::addChannel(Channel channel) {
  std::string text;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    channel.id = next_channel_++;
    channels_[channel.id] = channel;
    // Sent under the lock (the transport only queues), so no client sees a channel's
    // advertisement after its unadvertisement or before its serverInfo.
    text = advertiseMessage({channel});
    for (const auto& entry : clients_) transport_.sendText(entry.first, text);
  }
  return channel.id;
}

void BridgeCore::removeChannel(uint32_t channel_id) {
  bool had_subscribers = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (channels_.erase(channel_id) == 0) return;
    const auto subscribers = subscribers_.find(channel_id);
    if (subscribers != subscribers_.end()) {
      had_subscribers = !subscribers->second.empty();
      for (const auto& [client, subscription] : subscribers->second)
        clients_[client].subscriptions.erase(subscription);
      subscribers_.erase(subscribers);
    }
    const std::string text = unadvertiseMessage({channel_id});
    for (const auto& entry : clients_) transport_.sendText(entry.first, text);
  }
  if (had_subscribers) listener_.channelUnsubscribed(channel_id);
}

std::vector<Channel> BridgeCore::channels() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Channel> list;
  for (const auto& entry : channels_) list.push_back(entry.second);
  return list;
}

void BridgeCore::setServices(std::vector<ServiceDescription> services) {
  std::lock_guard<std::mutex> lock(mutex_);
  services_ = std::move(services);
}

bool BridgeCore::publish(uint32_t channel_id, uint64_t timestamp_ns, const uint8_t* payload,
                         size_t size, bool droppable) {
  std::vector<std::pair<ClientId, uint32_t>> targets;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = subscribers_.find(channel_id);
    if (it == subscribers_.end() || it->second.empty()) return false;
    targets.assign(it->second.begin(), it->second.end());
  }
  // One frame per client: the subscription id is in the header.
  for (const auto& [client, subscription] : targets)
    transport_.sendBinary(client, messageDataFrame(subscription, timestamp_ns, payload, size),
                          droppable);
  return true;
}

bool BridgeCore::hasSubscribers(uint32_t channel_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return subscribersLocked(channel_id) > 0;
}

size_t BridgeCore::subscribersLocked(uint32_t channel_id) const {
  const auto it = subscribers_.find(channel_id);
  return it == subscribers_.end() ? 0 : it->second.size();
}

void BridgeCore::clientConnected(ClientId client) {
  std::vector<std::string> texts;
  std::lock_guard<std::mutex> lock(mutex_);  // see addChannel
  {
    clients_[client];
    std::vector<std::string> capabilities;
    if (options_.services) capabilities.push_back("services");
    if (options_.parameters) capabilities.push_back("parameters");
    const auto session = std::chrono::system_clock::now().time_since_epoch().count();
    texts.push_back(serverInfoMessage(
        options_.name, capabilities,
        options_.services ? std::vector<std::string>{"json"} : std::vector<std::string>{},
        std::to_string(session), options_.metadata));
    std::vector<Channel> list;
    for (const auto& entry : channels_) list.push_back(entry.second);
    texts.push_back(advertiseMessage(list));  // the spec: at least one, even if empty
    if (options_.services && !services_.empty())
      texts.push_back(advertiseServicesMessage(services_));
  }
  for (const std::string& text : texts) transport_.sendText(client, text);
}

void BridgeCore::clientDisconnected(ClientId client) {
  std::vector<uint32_t> emptied;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = clients_.find(client);
    if (it == clients_.end()) return;
    for (const auto& [subscription, channel] : it->second.subscriptions) {
      auto& subscribers = subscribers_[channel];
      subscribers.erase(client);
      if (subscribers.empty()) {
        subscribers_.erase(channel);
        emptied.push_back(channel);
      }
    }
    clients_.erase(it);
  }
  for (uint32_t channel : emptied) listener_.channelUnsubscribed(channel);
}

void BridgeCore::sendStatus(ClientId client, StatusLevel level, const std::string& message) {
  if (level == StatusLevel::ERROR) ++protocol_errors_;
  transport_.sendText(client, statusMessage(level, message));
}

void BridgeCore::textMessage(ClientId client, const std::string& text) {
  try {
    handle(client, parseTextMessage(text));
  } catch (const ProtocolError& e) {
    sendStatus(client, StatusLevel::ERROR, e.what());
  }
}

void BridgeCore::binaryMessage(ClientId client, const uint8_t* data, size_t size) {
  try {
    handle(client, parseBinaryMessage(data, size));
  } catch (const ProtocolError& e) {
    sendStatus(client, StatusLevel::ERROR, e.what());
  }
}

void BridgeCore::handle(ClientId client, const ClientMessage& message) {
  if (const auto* s = std::get_if<Subscribe>(&message)) return subscribe(client, *s);
  if (const auto* u = std::get_if<Unsubscribe>(&message)) return unsubscribe(client, *u);
  if (const auto* call = std::get_if<ServiceCallRequest>(&message))
    return serviceCall(client, *call);
  if (const auto* unsupported = std::get_if<Unsupported>(&message))
    return sendStatus(client, StatusLevel::ERROR,
                      unsupported->op + ": not offered by this server (see its capabilities)");
  parameters(client, message);
}

void BridgeCore::subscribe(ClientId client, const Subscribe& request) {
  std::vector<uint32_t> first;
  std::vector<std::string> errors;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto& mine = clients_[client].subscriptions;
    for (const Subscribe::Entry& entry : request.subscriptions) {
      const std::string what = "subscribe: subscription " + std::to_string(entry.id) + ": ";
      if (!channels_.count(entry.channel_id)) {
        errors.push_back(what + "no channel " + std::to_string(entry.channel_id));
      } else if (mine.count(entry.id)) {
        errors.push_back(what + "id already in use");
      } else if (subscribers_[entry.channel_id].count(client)) {
        errors.push_back(what + "channel " + std::to_string(entry.channel_id) +
                         " already subscribed by this client");  // one per channel (spec)
      } else {
        mine[entry.id] = entry.channel_id;
        auto& subscribers = subscribers_[entry.channel_id];
        subscribers[client] = entry.id;
        if (subscribers.size() == 1) first.push_back(entry.channel_id);
      }
    }
  }
  for (const std::string& error : errors) sendStatus(client, StatusLevel::ERROR, error);
  for (uint32_t channel : first) listener_.channelSubscribed(channel);
}

void BridgeCore::unsubscribe(ClientId client, const Unsubscribe& request) {
  std::vector<uint32_t> emptied;
  std::vector<std::string> errors;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto& mine = clients_[client].subscriptions;
    for (uint32_t id : request.subscription_ids) {
      const auto it = mine.find(id);
      if (it == mine.end()) {
        errors.push_back("unsubscribe: no subscription " + std::to_string(id));
        continue;
      }
      auto& subscribers = subscribers_[it->second];
      subscribers.erase(client);
      if (subscribers.empty()) {
        subscribers_.erase(it->second);
        emptied.push_back(it->second);
      }
      mine.erase(it);
    }
  }
  for (const std::string& error : errors) sendStatus(client, StatusLevel::ERROR, error);
  for (uint32_t channel : emptied) listener_.channelUnsubscribed(channel);
}

void BridgeCore::parameters(ClientId client, const ClientMessage& message) {
  const bool get = std::holds_alternative<GetParameters>(message);
  const std::string op = get ? "getParameters" : "setParameters";
  if (!options_.parameters)
    return sendStatus(client, StatusLevel::ERROR,
                      op + ": parameters are not offered (the bridge's 'parameters' is false)");
  try {
    std::vector<std::string> names;
    std::string id;
    if (get) {
      names = std::get<GetParameters>(message).names;
      id = std::get<GetParameters>(message).id;
    } else {
      const auto& set = std::get<SetParameters>(message);
      listener_.setParameters(set);
      for (const auto& entry : set.parameters) names.push_back(entry.first);
      id = set.id;
    }
    transport_.sendText(client, parameterValuesMessage(listener_.getParameters(names), id));
  } catch (const std::exception& e) {
    sendStatus(client, StatusLevel::ERROR, op + ": " + e.what());
  }
}

void BridgeCore::serviceCall(ClientId client, const ServiceCallRequest& request) {
  bool known = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& service : services_) known = known || service.id == request.service_id;
  }
  if (!options_.services)
    return sendStatus(client, StatusLevel::ERROR,
                      "service call: services are not offered (the bridge's 'services' is false)");
  if (!known)
    return serviceFailure(client, request,
                          "no service with id " + std::to_string(request.service_id));
  if (request.encoding != "json")
    return serviceFailure(client, request,
                          "encoding '" + request.encoding + "': this server takes 'json'");
  listener_.callService(client, request);
}

void BridgeCore::serviceResponse(ClientId client, const ServiceCallRequest& request,
                                 const std::string& payload) {
  transport_.sendBinary(
      client, serviceCallResponseFrame(request.service_id, request.call_id, "json", payload),
      false);
}

void BridgeCore::serviceFailure(ClientId client, const ServiceCallRequest& request,
                                const std::string& message) {
  transport_.sendText(client,
                      serviceCallFailureMessage(request.service_id, request.call_id, message));
}

size_t BridgeCore::clientCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return clients_.size();
}

}  // namespace auv::foxglove_bridge
