// SPDX-License-Identifier: Apache-2.0
#include "request_router.hpp"

#include <spdlog/spdlog.h>

#include <utility>

#include "swivel/dds/topics.hpp"

namespace swivel::daemon {

std::optional<dds::ReplySample> RequestQueue::push(Request request) {
  {
    const std::lock_guard lock(mutex_);
    if (pending_.size() < kMaxPending) {
      pending_.push_back(std::move(request));
      return std::nullopt;
    }
  }
  // A flood of requests: answer the newest at once rather than queue without bound.
  dds::ReplySample busy;
  if (const auto* r = std::get_if<dds::RequestSample>(&request)) {
    busy.request_id = r->request_id;
    busy.verb = r->verb;
  } else {
    const auto& p = std::get<dds::SetPoseSample>(request);
    if (!p.wants_reply) return std::nullopt;
    busy.request_id = p.request_id;
    busy.verb = "set_pose";
  }
  busy.text = "refused: " + std::to_string(kMaxPending) + " requests are waiting; try again";
  return busy;
}

std::optional<RequestQueue::Request> RequestQueue::pop() {
  const std::lock_guard lock(mutex_);
  if (pending_.empty()) return std::nullopt;
  Request next = std::move(pending_.front());
  pending_.pop_front();
  return next;
}

dds::ReplySample route_request(const dds::RequestSample& request, bool stopping,
                               const RequestHandlers& handlers) {
  dds::ReplySample reply;
  if (stopping) {
    reply.text = "refused: swiveld is stopping";
  } else if (request.verb == "reload") {
    reply = handlers.reload();
  } else if (request.verb == "clear") {
    reply = handlers.clear(request.request_id);
  } else if (request.verb == "calibrate") {
    reply = handlers.calibrate(request.argument);
  } else {
    reply.text = "refused: unknown request '" + request.verb +
                 "' (reload, clear, calibrate; a pose goes to " + dds::kSetPoseTopic + ")";
  }
  reply.request_id = request.request_id;
  reply.verb = request.verb;
  if (reply.ok) {
    spdlog::info("{} request {}: {}", request.verb, request.request_id, reply.text);
  } else {
    spdlog::warn("{} request {}: {}", request.verb, request.request_id, reply.text);
  }
  return reply;
}

void answer_requests(RequestQueue& queue, const std::atomic<bool>& stopping,
                     const RequestHandlers& handlers,
                     const std::function<void(const dds::ReplySample&)>& publish) {
  while (auto next = queue.pop()) {
    dds::ReplySample reply;
    bool wants_reply = true;
    if (const auto* r = std::get_if<dds::RequestSample>(&*next)) {
      reply = route_request(*r, stopping.load(std::memory_order_acquire), handlers);
    } else {
      const auto& p = std::get<dds::SetPoseSample>(*next);
      reply = handlers.set_pose(p);
      wants_reply = p.wants_reply;
    }
    if (!wants_reply || !publish) continue;
    try {
      publish(reply);
    } catch (const std::exception& e) {
      spdlog::error("reply to {} request {} not published: {}", reply.verb, reply.request_id,
                    e.what());
    }
  }
}

}  // namespace swivel::daemon
