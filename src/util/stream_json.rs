//! Serialising a sequence from an iterator, one element at a time, without collecting it first: how the plan's
//! hash and the manifest are written for any number of clips in constant memory. [`Streamed`] serialises
//! exactly like a `Vec` of the same elements (the tests hold it to that), so the bytes do not depend on
//! whether a sequence was held or streamed.

use std::cell::RefCell;

use serde::ser::{Error as _, Serialize, SerializeSeq, Serializer};

/// A sequence serialised from an iterator of `Result`s, taken once: the first `Err` stops serialisation; it is
/// kept for [`Streamed::take_error`] (the serializer only sees a message). `len` is the number of elements
/// the iterator yields (serde's formats may write it first).
pub struct Streamed<I, E> {
    items: RefCell<Option<I>>,
    len: usize,
    error: RefCell<Option<E>>,
}

impl<I, T, E> Streamed<I, E>
where
    I: Iterator<Item = Result<T, E>>,
    T: Serialize,
    E: std::fmt::Display,
{
    /// The sequence of `len` elements that `items` yields.
    pub fn new(items: I, len: usize) -> Self {
        Streamed {
            items: RefCell::new(Some(items)),
            len,
            error: RefCell::new(None),
        }
    }

    /// The error that stopped serialisation, if an element was an `Err`.
    pub fn take_error(&self) -> Option<E> {
        self.error.borrow_mut().take()
    }
}

impl<I, T, E> Serialize for Streamed<I, E>
where
    I: Iterator<Item = Result<T, E>>,
    T: Serialize,
    E: std::fmt::Display,
{
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let items = self
            .items
            .borrow_mut()
            .take()
            .ok_or_else(|| S::Error::custom("a streamed sequence is serialised once"))?;
        let mut seq = serializer.serialize_seq(Some(self.len))?;
        for item in items {
            match item {
                Ok(item) => seq.serialize_element(&item)?,
                Err(e) => {
                    let message = e.to_string();
                    *self.error.borrow_mut() = Some(e);
                    return Err(S::Error::custom(message));
                }
            }
        }
        seq.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize)]
    struct Doc<C> {
        name: &'static str,
        items: C,
    }

    #[test]
    fn a_streamed_sequence_writes_the_bytes_of_the_collected_one() {
        for n in [0usize, 1, 3] {
            let held: Vec<(u32, String)> = (0..n as u32).map(|i| (i, format!("x{i}"))).collect();
            let streamed = Streamed::new(held.clone().into_iter().map(Ok::<_, String>), n);
            let doc = Doc {
                name: "d",
                items: &held,
            };
            let expected = (
                serde_json::to_string(&doc).expect("json"),
                serde_json::to_string_pretty(&doc).expect("json"),
            );
            let compact = serde_json::to_string(&Doc {
                name: "d",
                items: &streamed,
            })
            .expect("json");
            let streamed = Streamed::new(held.clone().into_iter().map(Ok::<_, String>), n);
            let pretty = serde_json::to_string_pretty(&Doc {
                name: "d",
                items: &streamed,
            })
            .expect("json");
            assert_eq!((compact, pretty), expected, "{n} elements");
        }
    }

    #[test]
    fn an_error_stops_serialisation_and_is_kept() {
        let items = vec![Ok(1), Err("disk on fire".to_owned()), Ok(3)];
        let streamed = Streamed::new(items.into_iter(), 3);
        let e = serde_json::to_string(&streamed).expect_err("fails");
        assert!(e.to_string().contains("disk on fire"), "{e}");
        assert_eq!(streamed.take_error().as_deref(), Some("disk on fire"));
        // Taken once.
        assert!(serde_json::to_string(&streamed).is_err());
    }
}
