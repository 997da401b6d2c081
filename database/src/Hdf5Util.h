// Hdf5Util.h — private helpers of the HDF5 layer (Hdf5Reader.h, Hdf5Writer.h) and the pack reader
// and writer: RAII ownership of HDF5 identifiers, a scope that silences HDF5's error printing, and
// the innermost message of the HDF5 error stack for our own typed errors.
#pragma once

#include <hdf5.h>

#include <string>
#include <utility>

namespace brittle::hdf5 {

/// Owns one hid_t and closes it with the matching H5?close function. Move-only.
class Handle {
 public:
  using CloseFn = herr_t (*)(hid_t);

  Handle() = default;
  Handle(hid_t id, CloseFn close) : mId(id), mClose(close) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& other) noexcept : mId(std::exchange(other.mId, H5I_INVALID_HID)), mClose(other.mClose) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      mId = std::exchange(other.mId, H5I_INVALID_HID);
      mClose = other.mClose;
    }
    return *this;
  }
  ~Handle() { reset(); }

  hid_t get() const { return mId; }
  bool valid() const { return mId >= 0; }

  /// Closes now and reports whether HDF5 accepted it. Closing a file flushes it, so the writer
  /// must see this result rather than leave it to the destructor.
  bool close() {
    if (!valid()) return true;
    const herr_t status = mClose(mId);
    mId = H5I_INVALID_HID;
    return status >= 0;
  }

 private:
  void reset() {
    if (valid()) mClose(mId);
    mId = H5I_INVALID_HID;
  }

  hid_t mId = H5I_INVALID_HID;
  CloseFn mClose = nullptr;
};

inline Handle fileHandle(hid_t id) { return Handle(id, H5Fclose); }
inline Handle groupHandle(hid_t id) { return Handle(id, H5Gclose); }
inline Handle datasetHandle(hid_t id) { return Handle(id, H5Dclose); }
inline Handle dataspaceHandle(hid_t id) { return Handle(id, H5Sclose); }
inline Handle datatypeHandle(hid_t id) { return Handle(id, H5Tclose); }
inline Handle attributeHandle(hid_t id) { return Handle(id, H5Aclose); }
inline Handle propertyHandle(hid_t id) { return Handle(id, H5Pclose); }

/// While alive, HDF5 does not print its error stack to stderr: every failure becomes a typed
/// brittle Error instead. The previous handler is restored so that a host application that
/// installed its own keeps it.
class ErrorSilencer {
 public:
  ErrorSilencer() {
    H5Eget_auto2(H5E_DEFAULT, &mOldFunc, &mOldData);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ErrorSilencer(const ErrorSilencer&) = delete;
  ErrorSilencer& operator=(const ErrorSilencer&) = delete;
  ~ErrorSilencer() { H5Eset_auto2(H5E_DEFAULT, mOldFunc, mOldData); }

 private:
  H5E_auto2_t mOldFunc = nullptr;
  void* mOldData = nullptr;
};

/// The innermost description on HDF5's current error stack ("" if empty), e.g. "data error
/// detected by Fletcher32 checksum". The innermost entry is the one that names the real cause;
/// the outer ones only repeat which API call failed.
inline std::string lastErrorDetail() {
  std::string detail;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t* err, void* data) -> herr_t {
        if (n == 0 && err && err->desc) *static_cast<std::string*>(data) = err->desc;
        return 0;
      },
      &detail);
  H5Eclear2(H5E_DEFAULT);
  return detail;
}

/// True when the innermost entry of HDF5's current error stack is a failure of the file's I/O
/// (major H5E_IO: the file driver could not read), as opposed to bad stored bytes (a checksum
/// failure is innermost "Data storage", under an outer H5E_IO entry). It leaves the stack.
inline bool lastErrorIsIo() {
  bool io = false;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t* err, void* data) -> herr_t {
        if (n == 0 && err && err->maj_num == H5E_IO) *static_cast<bool*>(data) = true;
        return 0;
      },
      &io);
  return io;
}

/// " (<detail>)" or "" — for appending the HDF5 cause to a message.
inline std::string withDetail() {
  const std::string detail = lastErrorDetail();
  return detail.empty() ? std::string() : " (" + detail + ")";
}

}  // namespace brittle::hdf5
