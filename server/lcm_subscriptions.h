#pragma once

// LCM subscriptions through LCM's C API. lcm-cpp's member-function subscriptions (typed and
// untyped) cast their user data in its own header in ways UBSan rejects (lcm-cpp-impl.hpp:88
// "member access within null pointer of type LCMMHSubscription", :108 "does not point to an
// object of type LCMMHUntypedSubscription"), which scripts/sanitize.sh turned into aborts of
// tangentd and tangent-phantom. Here the handler is a plain C callback with our own object.
// The raw form also lets a subscriber count packets that do not decode.

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

namespace tangent::server {

class LcmSubscriptions {
 public:
  /// `lcm` must outlive this object, and this object every message handled.
  explicit LcmSubscriptions(lcm::LCM* lcm) : lcm_(lcm) {}

  /// Every packet on `channel`: fn(data, size). `capacity`: LCM's queue for the channel (its
  /// default of 30 drops the newest messages at kilohertz rates).
  void Raw(const std::string& channel, std::function<void(const void*, uint32_t)> fn,
           int capacity = 10000) {
    handlers_.push_back(std::make_unique<Handler>(Handler{std::move(fn)}));
    lcm_subscription_t* s =
        lcm_subscribe(lcm_->getUnderlyingLCM(), channel.c_str(), &Dispatch, handlers_.back().get());
    lcm_subscription_set_queue_capacity(s, capacity);
  }

  /// Messages of type Msg on `channel`, decoded (packets that do not decode are dropped).
  template <class Msg>
  void Typed(const std::string& channel, std::function<void(const Msg&)> fn, int capacity = 10000) {
    auto msg = std::make_shared<Msg>();
    Raw(
        channel,
        [msg, fn = std::move(fn)](const void* data, uint32_t size) {
          if (msg->decode(data, 0, static_cast<int>(size)) >= 0) fn(*msg);
        },
        capacity);
  }

 private:
  struct Handler {
    std::function<void(const void*, uint32_t)> fn;
  };
  static void Dispatch(const lcm_recv_buf_t* rbuf, const char*, void* self) {
    static_cast<Handler*>(self)->fn(rbuf->data, rbuf->data_size);
  }

  lcm::LCM* lcm_;
  std::vector<std::unique_ptr<Handler>> handlers_;
};

}  // namespace tangent::server
