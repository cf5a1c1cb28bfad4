//! Safe RAII wrapper over OpenNI2's C API (feature `openni2`): initialise, list devices, open a
//! device or an `.oni` recording, start the depth stream, read frames with timestamps, seek,
//! record, close. Every handle is released by `Drop`, so nothing leaks on error paths; errors
//! carry OpenNI2's extended error text ([`KinectError::OpenNi`]).
//!
//! ```no_run
//! # fn main() -> Result<(), symcorr_kinect::KinectError> {
//! use symcorr_kinect::openni2::OpenNi;
//! let ni = OpenNi::init()?;
//! let device = ni.open("Dummy")?; // OpenNI2's built-in test device
//! let mut depth = device.depth_stream()?;
//! depth.start()?;
//! let frame = depth.read_frame(2000)?;
//! println!("{}x{} at {} µs", frame.depth.width, frame.depth.height, frame.timestamp_us);
//! # Ok(()) }
//! ```
//!
//! ## Behaviour of Debian's OpenNI 2.2.0.33 found on this machine (tests pin it down)
//!
//! * The `Dummy` driver is not enumerated by `oniGetDeviceList` (0 devices), but opening the URI
//!   `"Dummy"` works: one depth stream, 320×240 `DEPTH_1_MM`, 30 fps, timestamps 33 000 µs apart,
//!   frame indices from 1; it implements neither the FOV, cropping nor stride properties.
//! * Recording it with OpenNI2's own recorder (`oniCreateRecorder`) writes a valid `.oni`
//!   (the OniFile driver opens it and reports the right frame count, video mode and stride), but
//!   **playback delivers no frame at all**, at any `playbackSpeed` (1, 0 = fastest, −1 = manual)
//!   and with repeat on or off: OniFile's `PlayerStream::OnNewDataCallback` drops every frame when
//!   the recorded source has no `ONI_STREAM_PROPERTY_CROPPING` (it asks for it and returns on
//!   failure), and the recorder only records the properties the Dummy device implements. Reading
//!   then blocks forever (`oniStreamReadFrame`) or times out (`oniWaitForAnyStream`), and a
//!   seek blocks forever because the player thread never returns to its command loop. This
//!   wrapper therefore always waits with a timeout ([`DepthStream::read_frame`]) and reports
//!   [`KinectError::OpenNi`] with status `TIME_OUT` instead of hanging, and [`Device::seek`]
//!   refuses to seek a stream that has not produced a frame yet. This applies to recordings
//!   of the Dummy device only: a file with the cropping property (a real sensor's, or one of
//!   [`crate::oni_write`]) plays every frame, pixels and timestamps as written.
//! * `oniShutdown` crashes (SIGSEGV in a driver thread executing code of an already unloaded
//!   driver library) in a process that has used a recorder, whatever the teardown order, and
//!   also, racily, right after a Dummy stream was destroyed (`symcorr scan --device --uri Dummy`
//!   crashed at exit this way). This wrapper therefore initialises OpenNI2 once per process and
//!   never calls `oniShutdown`; the OS reclaims the library's state at exit.

use crate::depth::DepthFrame;
use crate::error::KinectError;
use std::ffi::{CStr, CString};
use std::marker::PhantomData;
use std::path::Path;
use std::sync::Mutex;
use symcorr_openni2_sys as sys;

/// OpenNI2's context is process-global: it is initialised by the first [`OpenNi::init`] and never
/// shut down (module docs).
static INITIALISED: Mutex<bool> = Mutex::new(false);

fn extended_error() -> String {
    // SAFETY: oniGetExtendedError returns a pointer to a NUL-terminated static/thread buffer
    // (or null); we copy it immediately.
    unsafe {
        let p = sys::oniGetExtendedError();
        if p.is_null() {
            String::new()
        } else {
            CStr::from_ptr(p).to_string_lossy().trim().to_string()
        }
    }
}

fn status_name(s: sys::OniStatus) -> &'static str {
    match s {
        sys::OniStatus::ONI_STATUS_OK => "OK",
        sys::OniStatus::ONI_STATUS_ERROR => "ERROR",
        sys::OniStatus::ONI_STATUS_NOT_IMPLEMENTED => "NOT_IMPLEMENTED",
        sys::OniStatus::ONI_STATUS_NOT_SUPPORTED => "NOT_SUPPORTED",
        sys::OniStatus::ONI_STATUS_BAD_PARAMETER => "BAD_PARAMETER",
        sys::OniStatus::ONI_STATUS_OUT_OF_FLOW => "OUT_OF_FLOW",
        sys::OniStatus::ONI_STATUS_NO_DEVICE => "NO_DEVICE",
        sys::OniStatus::ONI_STATUS_TIME_OUT => "TIME_OUT",
        _ => "UNKNOWN",
    }
}

fn check(call: &str, s: sys::OniStatus) -> Result<(), KinectError> {
    if s == sys::OniStatus::ONI_STATUS_OK {
        Ok(())
    } else {
        let text = extended_error();
        Err(KinectError::OpenNi {
            call: call.to_string(),
            status: s.0 as i32,
            message: if text.is_empty() {
                status_name(s).to_string()
            } else {
                format!("{}: {text}", status_name(s))
            },
        })
    }
}

/// Status code of a timed-out wait (`ONI_STATUS_TIME_OUT`), as found in [`KinectError::OpenNi`].
pub const STATUS_TIME_OUT: i32 = 102;

/// A handle on the initialised OpenNI2 library (process-global, initialised once, never shut
/// down: see the module docs). Devices borrow it, so it outlives them.
#[derive(Debug)]
pub struct OpenNi {
    _not_send: PhantomData<*const ()>,
}

/// A device found by [`OpenNi::devices`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceInfo {
    /// URI to pass to [`OpenNi::open`].
    pub uri: String,
    /// Vendor name.
    pub vendor: String,
    /// Device name.
    pub name: String,
    /// USB vendor id.
    pub usb_vendor_id: u16,
    /// USB product id.
    pub usb_product_id: u16,
}

fn c_chars(s: &[std::os::raw::c_char]) -> String {
    let bytes: Vec<u8> = s
        .iter()
        .take_while(|&&c| c != 0)
        .map(|&c| c as u8)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

impl OpenNi {
    /// Initialises OpenNI2 (`oniInitialize(ONI_API_VERSION)`); drivers are loaded from
    /// `/usr/lib/x86_64-linux-gnu/OpenNI2/Drivers` (Debian; see `/etc/openni2/OpenNI.ini`).
    pub fn init() -> Result<OpenNi, KinectError> {
        let mut done = INITIALISED.lock().unwrap_or_else(|e| e.into_inner());
        if !*done {
            // SAFETY: plain C call; the version constant matches the linked headers.
            check("oniInitialize", unsafe {
                sys::oniInitialize(sys::ONI_API_VERSION)
            })?;
            *done = true;
        }
        Ok(OpenNi {
            _not_send: PhantomData,
        })
    }

    /// The devices OpenNI2's drivers enumerate (the Dummy device is not among them).
    pub fn devices(&self) -> Result<Vec<DeviceInfo>, KinectError> {
        let mut list: *mut sys::OniDeviceInfo = std::ptr::null_mut();
        let mut n: i32 = 0;
        // SAFETY: out-pointers are valid; the list is released below.
        check("oniGetDeviceList", unsafe {
            sys::oniGetDeviceList(&mut list, &mut n)
        })?;
        let mut out = Vec::new();
        if !list.is_null() {
            for i in 0..n.max(0) as usize {
                // SAFETY: OpenNI2 allocated `n` entries at `list`.
                let d = unsafe { &*list.add(i) };
                out.push(DeviceInfo {
                    uri: c_chars(&d.uri),
                    vendor: c_chars(&d.vendor),
                    name: c_chars(&d.name),
                    usb_vendor_id: d.usbVendorId,
                    usb_product_id: d.usbProductId,
                });
            }
            // SAFETY: `list` came from oniGetDeviceList.
            unsafe { sys::oniReleaseDeviceList(list) };
        }
        Ok(out)
    }

    /// Opens a device by URI (from [`OpenNi::devices`], `"Dummy"`, or a `.oni` file path).
    pub fn open(&self, uri: &str) -> Result<Device<'_>, KinectError> {
        let c = CString::new(uri).map_err(|_| KinectError::OpenNi {
            call: "oniDeviceOpen".into(),
            status: 4,
            message: format!("URI {uri:?} contains a NUL byte"),
        })?;
        let mut h: sys::OniDeviceHandle = std::ptr::null_mut();
        // SAFETY: valid C string and out-pointer.
        check(&format!("oniDeviceOpen({uri})"), unsafe {
            sys::oniDeviceOpen(c.as_ptr(), &mut h)
        })?;
        Ok(Device {
            handle: h,
            uri: uri.to_string(),
            _ctx: PhantomData,
        })
    }

    /// Opens an `.oni` recording (checks that the file exists first, so the error names it).
    pub fn open_file(&self, path: impl AsRef<Path>) -> Result<Device<'_>, KinectError> {
        let p = path.as_ref();
        let file = p.display().to_string();
        std::fs::metadata(p).map_err(|e| KinectError::io(&file, e))?;
        self.open(&file)
    }
}

/// An open device or recording. Closed on drop.
#[derive(Debug)]
pub struct Device<'ctx> {
    handle: sys::OniDeviceHandle,
    uri: String,
    _ctx: PhantomData<&'ctx OpenNi>,
}

impl Device<'_> {
    /// The URI it was opened with.
    pub fn uri(&self) -> &str {
        &self.uri
    }

    /// Whether this is a recording (it supports the playback-speed property).
    pub fn is_file(&self) -> bool {
        // SAFETY: valid handle.
        unsafe {
            sys::oniDeviceIsPropertySupported(
                self.handle,
                sys::ONI_DEVICE_PROPERTY_PLAYBACK_SPEED as i32,
            ) != 0
        }
    }

    /// Playback speed of a recording: 1 real time, 0 as fast as possible, −1 manual.
    pub fn set_playback_speed(&self, speed: f32) -> Result<(), KinectError> {
        // SAFETY: the property is a float.
        check("oniDeviceSetProperty(PLAYBACK_SPEED)", unsafe {
            sys::oniDeviceSetProperty(
                self.handle,
                sys::ONI_DEVICE_PROPERTY_PLAYBACK_SPEED as i32,
                (&speed as *const f32).cast(),
                std::mem::size_of::<f32>() as i32,
            )
        })
    }

    /// Whether a recording restarts at its end.
    pub fn set_repeat(&self, repeat: bool) -> Result<(), KinectError> {
        let v: sys::OniBool = i32::from(repeat);
        // SAFETY: the property is an OniBool (int).
        check("oniDeviceSetProperty(PLAYBACK_REPEAT_ENABLED)", unsafe {
            sys::oniDeviceSetProperty(
                self.handle,
                sys::ONI_DEVICE_PROPERTY_PLAYBACK_REPEAT_ENABLED as i32,
                (&v as *const sys::OniBool).cast(),
                std::mem::size_of::<sys::OniBool>() as i32,
            )
        })
    }

    /// Creates the depth stream (not started).
    pub fn depth_stream(&self) -> Result<DepthStream<'_>, KinectError> {
        self.depth_stream_unbound()
    }

    /// The depth stream with a lifetime of the caller's choosing: only for owners that keep the
    /// stream and the device together and destroy the stream first ([`FilePlayback`]).
    fn depth_stream_unbound<'dev>(&self) -> Result<DepthStream<'dev>, KinectError> {
        let mut h: sys::OniStreamHandle = std::ptr::null_mut();
        // SAFETY: valid device handle and out-pointer.
        check("oniDeviceCreateStream(DEPTH)", unsafe {
            sys::oniDeviceCreateStream(self.handle, sys::OniSensorType::ONI_SENSOR_DEPTH, &mut h)
        })?;
        Ok(DepthStream {
            handle: h,
            started: false,
            frames_read: 0,
            _dev: PhantomData,
        })
    }

    /// Seeks a recording so that the next frame `stream` delivers is `frame_index` (OpenNI2's
    /// 1-based index). Refused (error) before the stream has delivered a frame: OniFile's seek
    /// blocks forever when its player thread is not running (module docs).
    pub fn seek(&self, stream: &DepthStream<'_>, frame_index: i32) -> Result<(), KinectError> {
        if stream.frames_read == 0 {
            return Err(KinectError::OpenNi {
                call: "oniDeviceInvoke(SEEK)".into(),
                status: sys::OniStatus::ONI_STATUS_OUT_OF_FLOW.0 as i32,
                message: "refusing to seek before the stream has delivered a frame \
                          (OpenNI2's file player would block forever)"
                    .into(),
            });
        }
        let mut seek = sys::OniSeek {
            frameIndex: frame_index,
            stream: stream.handle,
        };
        // SAFETY: OniSeek is the documented argument of ONI_DEVICE_COMMAND_SEEK.
        check("oniDeviceInvoke(SEEK)", unsafe {
            sys::oniDeviceInvoke(
                self.handle,
                sys::ONI_DEVICE_COMMAND_SEEK as i32,
                (&mut seek as *mut sys::OniSeek).cast(),
                std::mem::size_of::<sys::OniSeek>() as i32,
            )
        })
    }
}

impl Drop for Device<'_> {
    fn drop(&mut self) {
        // SAFETY: streams borrow the device and are gone; the handle is valid.
        unsafe { sys::oniDeviceClose(self.handle) };
    }
}

/// A depth frame read from a stream.
#[derive(Debug, Clone, PartialEq)]
pub struct StampedDepth {
    /// The depth image (millimetres).
    pub depth: DepthFrame,
    /// Device timestamp in microseconds.
    pub timestamp_us: u64,
    /// OpenNI2's frame index.
    pub frame_index: i32,
}

/// Video mode of a stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VideoMode {
    /// Width in pixels.
    pub width: i32,
    /// Height in pixels.
    pub height: i32,
    /// Frames per second.
    pub fps: i32,
    /// OpenNI2 pixel format code (100 = DEPTH_1_MM, 101 = DEPTH_100_UM).
    pub pixel_format: u32,
}

/// A depth stream; stopped and destroyed on drop.
#[derive(Debug)]
pub struct DepthStream<'dev> {
    handle: sys::OniStreamHandle,
    started: bool,
    frames_read: u64,
    _dev: PhantomData<&'dev ()>,
}

impl DepthStream<'_> {
    fn get_int(&self, prop: u32) -> Option<i32> {
        let mut v: i32 = 0;
        let mut size = std::mem::size_of::<i32>() as i32;
        // SAFETY: int-valued property.
        let s = unsafe {
            sys::oniStreamGetProperty(
                self.handle,
                prop as i32,
                (&mut v as *mut i32).cast(),
                &mut size,
            )
        };
        (s == sys::OniStatus::ONI_STATUS_OK).then_some(v)
    }

    fn get_float(&self, prop: u32) -> Option<f32> {
        let mut v: f32 = 0.0;
        let mut size = std::mem::size_of::<f32>() as i32;
        // SAFETY: float-valued property.
        let s = unsafe {
            sys::oniStreamGetProperty(
                self.handle,
                prop as i32,
                (&mut v as *mut f32).cast(),
                &mut size,
            )
        };
        (s == sys::OniStatus::ONI_STATUS_OK).then_some(v)
    }

    /// The stream's video mode.
    pub fn video_mode(&self) -> Result<VideoMode, KinectError> {
        // SAFETY: zeroed plain-data struct used as an out-parameter.
        let mut vm: sys::OniVideoMode = unsafe { std::mem::zeroed() };
        let mut size = std::mem::size_of::<sys::OniVideoMode>() as i32;
        // SAFETY: the property is an OniVideoMode.
        check("oniStreamGetProperty(VIDEO_MODE)", unsafe {
            sys::oniStreamGetProperty(
                self.handle,
                sys::ONI_STREAM_PROPERTY_VIDEO_MODE as i32,
                (&mut vm as *mut sys::OniVideoMode).cast(),
                &mut size,
            )
        })?;
        Ok(VideoMode {
            width: vm.resolutionX,
            height: vm.resolutionY,
            fps: vm.fps,
            pixel_format: vm.pixelFormat.0,
        })
    }

    /// Number of frames of a recording's stream (`None` for live devices).
    pub fn number_of_frames(&self) -> Option<i32> {
        self.get_int(sys::ONI_STREAM_PROPERTY_NUMBER_OF_FRAMES)
    }

    /// Horizontal and vertical field of view in radians, if the driver reports them (the Dummy
    /// device does not).
    pub fn field_of_view(&self) -> Option<(f32, f32)> {
        Some((
            self.get_float(sys::ONI_STREAM_PROPERTY_HORIZONTAL_FOV)?,
            self.get_float(sys::ONI_STREAM_PROPERTY_VERTICAL_FOV)?,
        ))
    }

    /// The stream's mirroring (`ONI_STREAM_PROPERTY_MIRRORING`), if the driver reports it:
    /// `Some(true)` for an image shown as in a mirror, the Kinect SDK's (the Kinect drivers
    /// always report it), `Some(false)` for the image as the lens forms it. The Dummy device
    /// reports none.
    pub fn mirroring(&self) -> Option<bool> {
        self.get_int(sys::ONI_STREAM_PROPERTY_MIRRORING)
            .map(|v| v != 0)
    }

    /// Starts streaming.
    pub fn start(&mut self) -> Result<(), KinectError> {
        // SAFETY: valid stream handle.
        check("oniStreamStart", unsafe {
            sys::oniStreamStart(self.handle)
        })?;
        self.started = true;
        Ok(())
    }

    /// Stops streaming.
    pub fn stop(&mut self) {
        if self.started {
            // SAFETY: valid, started stream.
            unsafe { sys::oniStreamStop(self.handle) };
            self.started = false;
        }
    }

    /// Waits up to `timeout_ms` for the next frame and copies it out (the OpenNI2 frame is
    /// released before returning). Timeout → [`KinectError::OpenNi`] with status
    /// [`STATUS_TIME_OUT`].
    pub fn read_frame(&mut self, timeout_ms: i32) -> Result<StampedDepth, KinectError> {
        let mut handle = self.handle;
        let mut index: i32 = -1;
        // SAFETY: one valid stream handle; out-pointer valid.
        check("oniWaitForAnyStream", unsafe {
            sys::oniWaitForAnyStream(&mut handle, 1, &mut index, timeout_ms)
        })?;
        let mut frame: *mut sys::OniFrame = std::ptr::null_mut();
        // SAFETY: a frame is ready, so this does not block; out-pointer valid.
        check("oniStreamReadFrame", unsafe {
            sys::oniStreamReadFrame(self.handle, &mut frame)
        })?;
        struct Release(*mut sys::OniFrame);
        impl Drop for Release {
            fn drop(&mut self) {
                // SAFETY: the frame came from oniStreamReadFrame and is released exactly once.
                unsafe { sys::oniFrameRelease(self.0) };
            }
        }
        if frame.is_null() {
            return Err(KinectError::OpenNi {
                call: "oniStreamReadFrame".into(),
                status: 1,
                message: "returned no frame".into(),
            });
        }
        let guard = Release(frame);
        // SAFETY: non-null frame owned by `guard` until the end of this function.
        let f = unsafe { &*guard.0 };
        let bad = |message: String| KinectError::OpenNi {
            call: "oniStreamReadFrame".into(),
            status: 1,
            message,
        };
        let format = f.videoMode.pixelFormat.0;
        let scale_um = match format {
            100 => 1000u32, // DEPTH_1_MM
            101 => 100,     // DEPTH_100_UM
            _ => return Err(bad(format!("pixel format {format} is not a depth format"))),
        };
        let (w, h, stride) = (f.width, f.height, f.stride);
        if w <= 0 || h <= 0 || stride < 2 * w || f.data.is_null() {
            return Err(bad(format!("frame {w}x{h} with stride {stride}")));
        }
        let needed = stride as usize * (h as usize - 1) + 2 * w as usize;
        if (f.dataSize as usize) < needed {
            return Err(bad(format!(
                "frame {w}x{h} stride {stride} has only {} bytes",
                f.dataSize
            )));
        }
        // SAFETY: `dataSize` bytes are readable at `data` (checked to cover every row).
        let bytes = unsafe { std::slice::from_raw_parts(f.data as *const u8, f.dataSize as usize) };
        let mut data = Vec::with_capacity(w as usize * h as usize);
        for row in 0..h as usize {
            let line = &bytes[row * stride as usize..row * stride as usize + 2 * w as usize];
            data.extend(line.chunks_exact(2).map(|c| {
                let raw = u16::from_ne_bytes([c[0], c[1]]) as u32;
                (raw * scale_um / 1000).min(u16::MAX as u32) as u16
            }));
        }
        let out = StampedDepth {
            depth: DepthFrame::new(w as u32, h as u32, data)?,
            timestamp_us: f.timestamp,
            frame_index: f.frameIndex,
        };
        drop(guard);
        self.frames_read += 1;
        Ok(out)
    }
}

impl Drop for DepthStream<'_> {
    fn drop(&mut self) {
        self.stop();
        // SAFETY: valid handle, destroyed exactly once.
        unsafe { sys::oniStreamDestroy(self.handle) };
    }
}

/// OpenNI2's own `.oni` recorder. Destroyed (file finalised) on drop.
#[derive(Debug)]
pub struct Recorder<'ctx> {
    handle: sys::OniRecorderHandle,
    started: bool,
    _ctx: PhantomData<&'ctx OpenNi>,
}

impl<'ctx> Recorder<'ctx> {
    /// Creates a recorder writing to `path`.
    pub fn create(
        _ni: &'ctx OpenNi,
        path: impl AsRef<Path>,
    ) -> Result<Recorder<'ctx>, KinectError> {
        let file = path.as_ref().display().to_string();
        let c = CString::new(file.clone()).map_err(|_| KinectError::OpenNi {
            call: "oniCreateRecorder".into(),
            status: 4,
            message: format!("path {file:?} contains a NUL byte"),
        })?;
        let mut h: sys::OniRecorderHandle = std::ptr::null_mut();
        // SAFETY: valid C string and out-pointer.
        check(&format!("oniCreateRecorder({file})"), unsafe {
            sys::oniCreateRecorder(c.as_ptr(), &mut h)
        })?;
        Ok(Recorder {
            handle: h,
            started: false,
            _ctx: PhantomData,
        })
    }

    /// Attaches a stream (lossless).
    pub fn attach(&mut self, stream: &DepthStream<'_>) -> Result<(), KinectError> {
        // SAFETY: both handles valid.
        check("oniRecorderAttachStream", unsafe {
            sys::oniRecorderAttachStream(self.handle, stream.handle, 0)
        })
    }

    /// Starts recording frames of the attached streams.
    pub fn start(&mut self) -> Result<(), KinectError> {
        // SAFETY: valid recorder.
        check("oniRecorderStart", unsafe {
            sys::oniRecorderStart(self.handle)
        })?;
        self.started = true;
        Ok(())
    }

    /// Stops recording.
    pub fn stop(&mut self) {
        if self.started {
            // SAFETY: valid, started recorder.
            unsafe { sys::oniRecorderStop(self.handle) };
            self.started = false;
        }
    }
}

impl Drop for Recorder<'_> {
    fn drop(&mut self) {
        self.stop();
        // SAFETY: valid handle; oniRecorderDestroy flushes the file and frees the recorder.
        unsafe { sys::oniRecorderDestroy(&mut self.handle) };
    }
}

/// An `.oni` recording opened for reading its depth frames one after another: the device and its
/// started depth stream in one owner, so that a reader can keep them in a struct (a
/// [`DepthStream`] otherwise borrows its [`Device`]). Playback is manual (speed −1): OpenNI2's
/// file player hands over the next frame only when [`FilePlayback::read_frame`] waits for one,
/// so a slow reader loses no frame (at speed 0 or 1 the player overwrites unread frames). No
/// repeat: the end of the file is a timeout, not frame 1 again.
#[derive(Debug)]
pub struct FilePlayback {
    // Declared before `device`: dropped (stopped, destroyed) before the device is closed.
    stream: DepthStream<'static>,
    device: Device<'static>,
}

impl FilePlayback {
    /// Opens `path` ([`OpenNi::open_file`]) and starts its depth stream in manual playback.
    pub fn open(path: impl AsRef<Path>) -> Result<FilePlayback, KinectError> {
        // The context is process-wide and never shut down (module docs), so a 'static handle
        // on it is the truth; `OpenNi` has no data, so leaking it allocates nothing.
        let ni: &'static OpenNi = Box::leak(Box::new(OpenNi::init()?));
        let device = ni.open_file(path)?;
        device.set_playback_speed(-1.0)?;
        device.set_repeat(false)?;
        let mut stream = device.depth_stream_unbound()?;
        stream.start()?;
        Ok(FilePlayback { stream, device })
    }

    /// The recording's device (for [`Device::uri`] and the playback properties).
    pub fn device(&self) -> &Device<'static> {
        &self.device
    }

    /// The depth stream (video mode, field of view, number of frames).
    pub fn stream(&self) -> &DepthStream<'static> {
        &self.stream
    }

    /// The next frame of the recording ([`DepthStream::read_frame`]).
    pub fn read_frame(&mut self, timeout_ms: i32) -> Result<StampedDepth, KinectError> {
        self.stream.read_frame(timeout_ms)
    }
}
