#pragma once
// Conversions from the uncompressed formats UVC cameras deliver into the
// decoder's BGR8 layout. They write into a buffer the caller allocated once
// (in V4l2Camera::configure()), so capturing never allocates.

#include "pipeline/frame.hpp"

namespace stria::hal {

// YUYV 4:2:2 (Y0 U Y1 V per pixel pair), BT.601 limited range (Y 16..235,
// Cb/Cr 16..240): what UVC cameras send. Fixed point, 8 fractional bits; at
// most 1 level from the exact transform. src.width must be even.
void convertYuyvToBgr(const FrameView& src, const MutableFrameView& dst);

// RGB24 -> BGR8 (swap R and B) and BGR24 -> BGR8 (row copy honouring strides).
void convertRgbToBgr(const FrameView& src, const MutableFrameView& dst);
void copyBgr(const FrameView& src, const MutableFrameView& dst);

}  // namespace stria::hal
