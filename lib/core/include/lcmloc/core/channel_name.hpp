#pragma once
// The name of a channel an input came on, stored once per process: every input carries one, and
// the engine copies, moves and compares them per message, so a copy is a pointer and equality a
// pointer comparison. Making one from a string looks the name up in the process's table (a lock
// and a hash): a caller that makes one per message keeps the last one made (see DaemonIntake).
#include <ostream>
#include <string>
#include <string_view>

namespace lcmloc::core {

class ChannelName {
 public:
  ChannelName() : p_(&intern({})) {}
  ChannelName(std::string_view name) : p_(&intern(name)) {}      // NOLINT: implicit on purpose
  ChannelName(const std::string& name) : p_(&intern(name)) {}    // NOLINT
  ChannelName(const char* name) : p_(&intern(name)) {}           // NOLINT

  const std::string& str() const { return *p_; }
  operator const std::string&() const { return *p_; }  // NOLINT: a name is a string
  const char* c_str() const { return p_->c_str(); }
  bool empty() const { return p_->empty(); }
  std::size_t size() const { return p_->size(); }

  friend bool operator==(const ChannelName& a, const ChannelName& b) { return a.p_ == b.p_; }
  friend bool operator!=(const ChannelName& a, const ChannelName& b) { return a.p_ != b.p_; }
  friend bool operator==(const ChannelName& a, const std::string& b) { return *a.p_ == b; }
  friend bool operator==(const std::string& a, const ChannelName& b) { return a == *b.p_; }
  friend bool operator!=(const ChannelName& a, const std::string& b) { return *a.p_ != b; }
  friend bool operator!=(const std::string& a, const ChannelName& b) { return a != *b.p_; }
  friend bool operator==(const ChannelName& a, const char* b) { return *a.p_ == b; }
  friend bool operator!=(const ChannelName& a, const char* b) { return *a.p_ != b; }
  friend bool operator<(const ChannelName& a, const ChannelName& b) { return *a.p_ < *b.p_; }
  friend std::string operator+(const ChannelName& a, const std::string& b) { return *a.p_ + b; }
  friend std::string operator+(const ChannelName& a, const char* b) { return *a.p_ + b; }
  friend std::string operator+(const std::string& a, const ChannelName& b) { return a + *b.p_; }
  friend std::string operator+(const char* a, const ChannelName& b) { return a + *b.p_; }
  friend std::ostream& operator<<(std::ostream& os, const ChannelName& n) { return os << *n.p_; }

 private:
  /// The process's one copy of name (created on first use, kept until the process ends).
  static const std::string& intern(std::string_view name);
  const std::string* p_;
};

}  // namespace lcmloc::core
