//! How per-instance arrays larger than one storage binding are bound: as several
//! windows of one buffer, each a power-of-two count of elements.

/// The per-instance arrays that may outgrow the device's largest storage binding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Windowed {
    /// Instance records ([`crate::records::InstanceRecord`]).
    Instances,
    /// World bounding spheres, 16 bytes each.
    Spheres,
}

impl Windowed {
    /// Bytes per element.
    pub fn stride(self) -> u64 {
        match self {
            Windowed::Instances => size_of::<crate::records::InstanceRecord>() as u64,
            Windowed::Spheres => 16,
        }
    }
}

/// How one windowed array is bound: `count` bindings of `1 << shift` elements each
/// (the last may hold fewer); one window binds the buffer whole.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    /// Bindings.
    pub count: u32,
    /// Elements per binding: `1 << shift`.
    pub shift: u32,
}

impl Window {
    /// One binding over the whole buffer.
    pub const WHOLE: Window = Window {
        count: 1,
        shift: 31,
    };

    /// Windows for `slots` elements of `stride` bytes, at most `limit` bytes a binding.
    pub fn new(slots: u32, stride: u64, limit: u64) -> Window {
        let per = (limit / stride).max(1);
        let shift = (u64::BITS - 1 - per.leading_zeros()).min(31);
        match (slots as u64).div_ceil(1 << shift) {
            0 | 1 => Window::WHOLE,
            count => Window {
                count: count as u32,
                shift,
            },
        }
    }
}

/// How every windowed array of a renderer is bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Windows {
    /// The instance records'.
    pub instances: Window,
    /// The world spheres'.
    pub spheres: Window,
}

impl Windows {
    /// Every array bound whole.
    pub const WHOLE: Windows = Windows {
        instances: Window::WHOLE,
        spheres: Window::WHOLE,
    };

    /// For `slots` instances with bindings of at most `limit` bytes.
    pub fn new(slots: u32, limit: u64) -> Windows {
        let of = |w: Windowed| Window::new(slots, w.stride(), limit);
        Windows {
            instances: of(Windowed::Instances),
            spheres: of(Windowed::Spheres),
        }
    }

    /// How `windowed` is bound.
    pub fn of(&self, windowed: Windowed) -> Window {
        match windowed {
            Windowed::Instances => self.instances,
            Windowed::Spheres => self.spheres,
        }
    }
}
