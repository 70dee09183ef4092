//! The stack of the wide walks, on storage that is never cleared. A walk
//! bounds its depth by the tree's (128 entries for the usual trees), and
//! zeroing that much storage before every ray cost about a hundred
//! instructions, as much as a node visit; a ray rarely uses more than a
//! dozen entries. So only pushed entries are ever
//! written, and only written ones are read.

use std::mem::MaybeUninit;

/// A stack over borrowed, uninitialised slots. Invariant: the first `len`
/// slots hold values written by [`UninitStack::push`].
pub struct UninitStack<'a, T> {
    slots: &'a mut [MaybeUninit<T>],
    len: usize,
}

impl<'a, T: Copy> UninitStack<'a, T> {
    pub fn new(slots: &'a mut [MaybeUninit<T>]) -> UninitStack<'a, T> {
        UninitStack { slots, len: 0 }
    }

    /// Panics when the slots are full.
    #[inline(always)]
    pub fn push(&mut self, value: T) {
        self.slots[self.len] = MaybeUninit::new(value);
        self.len += 1;
    }

    #[inline(always)]
    pub fn pop(&mut self) -> Option<T> {
        self.len = self.len.checked_sub(1)?;
        // SAFETY: the slot is below the old `len`, so `push` wrote it.
        Some(unsafe { self.slots[self.len].assume_init() })
    }

    /// The value on top, to change in place.
    #[inline(always)]
    pub fn top_mut(&mut self) -> Option<&mut T> {
        let top = self.len.checked_sub(1)?;
        // SAFETY: the slot is below `len`, so `push` wrote it.
        Some(unsafe { self.slots[top].assume_init_mut() })
    }

    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// The values pushed since the stack held `from`, to reorder in place.
    /// Panics if `from` is above the stack's length.
    #[inline(always)]
    pub fn pushed_since(&mut self, from: usize) -> &mut [T] {
        let pushed = &mut self.slots[from..self.len];
        // SAFETY: these slots are below `len`, so `push` wrote them; and
        // `MaybeUninit<T>` has the size, alignment and layout of `T`.
        unsafe { &mut *(pushed as *mut [MaybeUninit<T>] as *mut [T]) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_what_was_pushed_last_first_and_reorders_the_top() {
        let mut slots = [MaybeUninit::uninit(); 4];
        let mut stack = UninitStack::new(&mut slots);
        assert_eq!(stack.pop(), None);
        stack.push(1);
        stack.push(2);
        stack.push(4);
        *stack.top_mut().expect("a top") -= 1;
        stack.pushed_since(1).reverse();
        assert_eq!(stack.len(), 3);
        assert_eq!(
            [stack.pop(), stack.pop(), stack.pop()],
            [Some(2), Some(3), Some(1)]
        );
        assert_eq!(stack.pop(), None);
    }

    #[test]
    #[should_panic]
    fn panics_when_full() {
        let mut slots = [MaybeUninit::uninit(); 1];
        let mut stack = UninitStack::new(&mut slots);
        stack.push(1);
        stack.push(2);
    }
}
