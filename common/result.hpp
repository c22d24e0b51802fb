// Result<T>: the error style of every library layer (docs/architecture.md §13). A function that can fail on
// input or I/O returns Result<T>: either a value or an Error with a code and a human message.
// The CLI maps codes to exit codes, the server to HTTP statuses. Invariants use assert instead.
// Thread safety: plain value types.
#pragma once

#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace shadowtiles {

enum class ErrorCode {
  invalid_input,  // the caller's data or parameters are malformed (scene file, query, config)
  corrupt_data,   // stored bytes fail a header, size or checksum check
  not_found,      // a key, file or tile that does not exist
  io_error,       // the OS or a library refused (open, read, write, LMDB)
  out_of_space,   // disk or map full after growing
  unsupported,    // a valid request this build cannot serve (unknown method, newer format)
};

const char* error_code_name(ErrorCode code);

struct Error {
  ErrorCode code;
  std::string message;
};

template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::move(value)) {}
  Result(Error error) : state_(std::move(error)) {}

  bool ok() const { return state_.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & { assert(ok()); return std::get<0>(state_); }
  const T& value() const& { assert(ok()); return std::get<0>(state_); }
  T&& value() && { assert(ok()); return std::get<0>(std::move(state_)); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

  const Error& error() const { assert(!ok()); return std::get<1>(state_); }

 private:
  std::variant<T, Error> state_;
};

// Result<void> equivalent.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error)), ok_(false) {}
  static Status success() { return {}; }
  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const Error& error() const { assert(!ok_); return error_; }

 private:
  Error error_{ErrorCode::invalid_input, {}};
  bool ok_ = true;
};

inline Error make_error(ErrorCode code, std::string message) { return Error{code, std::move(message)}; }

}  // namespace shadowtiles
